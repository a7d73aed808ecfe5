#!/usr/bin/python3
"""The nodes refuse bad parameters at start-up, and ekf_slam_node takes a
good initial_map's grid.

ekf_slam_node and feature_node, the two drivers (p3dx_driver_node,
lms200_node) and simulator_node, which share the same parameter reader.

Each case starts the node with one bad private parameter (or a bad
configuration file) against the rostest roscore and asserts that it exits
with code 1 and that its error names the offending key.
"""
import os
import signal
import subprocess
import tempfile
import time
import unittest

import rostest


RUNS = [0]


def run_node(node_type, *args):
    """Runs the node until it exits (at most 30 s); returns (code, output).

    Each run gets its own node name: private parameters stay on the
    parameter server after a node exits and would leak into the next case.
    """
    RUNS[0] += 1
    name = "param_check_%s_%d" % (node_type, RUNS[0])
    command = ["rosrun", "ekf_slam", node_type, "__name:=" + name] + list(args)
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            timeout=30, text=True)
    return result.returncode, result.stdout


class BadParameters(unittest.TestCase):
    def check(self, node_type, expected, *args):
        code, output = run_node(node_type, *args)
        self.assertEqual(code, 1, "%s %s should exit with 1:\n%s" % (node_type, args, output))
        self.assertIn(expected, output)

    def test_out_of_range_value_names_the_key(self):
        self.check("ekf_slam_node", "tf_timeout", "_tf_timeout:=-1.0")

    def test_too_short_tf_cache_names_the_key(self):
        self.check("ekf_slam_node", "tf_cache_time", "_tf_cache_time:=0.5")

    def test_unknown_key_names_the_key(self):
        self.check("ekf_slam_node", "tf_timout", "_tf_timout:=0.5")

    def test_negative_history_bound_names_the_key(self):
        self.check("ekf_slam_node", "history_max_scans", "_history_max_scans:=-1")

    def test_wrong_type_names_the_key(self):
        self.check("ekf_slam_node", "scan_queue_size", "_scan_queue_size:=many")

    def test_a_fraction_where_an_integer_is_declared_is_refused(self):
        # Not rounded to 2 or 3: the value is refused, naming the key.
        self.check("ekf_slam_node", "scan_queue_size: must be an integer, got 2.5",
                   "_scan_queue_size:=2.5")
        self.check("lms200_node", "angle: must be an integer, got 180.5", "_angle:=180.5",
                   "_port:=/dev/null")

    def test_same_frames_are_refused(self):
        self.check("ekf_slam_node", "map_frame", "_map_frame:=odom")

    def test_bad_configuration_file_names_the_yaml_key(self):
        with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
            f.write("filter:\n  motion_noise:\n    rot_per_rot: -1\n")
            path = f.name
        try:
            self.check("ekf_slam_node", "filter.motion_noise.rot_per_rot",
                       "_config_file:=" + path)
            self.check("feature_node", "filter.motion_noise.rot_per_rot",
                       "_config_file:=" + path)
        finally:
            os.unlink(path)

    def test_bad_value_under_the_slam_namespace_names_the_yaml_key(self):
        # The launch files load the configuration file into ~slam; the nodes
        # read it from there (so rosparam get shows it), checked alike.
        self.check("ekf_slam_node", "filter.motion_noise.rot_per_rot",
                   "_slam/filter/motion_noise/rot_per_rot:=-1")
        self.check("feature_node", "features.split_threshold",
                   "_slam/features/split_threshold:=-0.5")

    def test_unknown_input_mode_names_the_key(self):
        self.check("ekf_slam_node", "input", "_input:=laser")

    def test_features_input_with_scan_matching_names_the_conflict(self):
        # The built-in defaults have scan matching on; it needs the scans.
        self.check("ekf_slam_node", "scan_matching.enabled", "_input:=features")

    def test_rear_laser_parameters_name_the_key(self):
        # The merge works on the raw scans, from another topic than the scan's.
        self.check("ekf_slam_node", "rear_scan_topic", "_rear_scan_topic:=scan_rear",
                   "_input:=features")
        self.check("ekf_slam_node", "rear_scan_topic", "_rear_scan_topic:=scan")
        self.check("ekf_slam_node", "merged_angle_increment", "_merged_angle_increment:=2.0")
        self.check("ekf_slam_node", "rear_scan_tolerance", "_rear_scan_tolerance:=-0.1")
        # The simulator's rear scanner needs its mount.
        self.check("simulator_node", "rear_calibration_file",
                   "_rear_lms200_link:=/tmp/ekf_slam_params_rear", "_world_file:=/nonexistent",
                   "_calibration_file:=/nonexistent")

    def test_unreadable_initial_map_is_reported(self):
        self.check("ekf_slam_node", "/nonexistent/landmarks.yaml",
                   "_initial_map:=/nonexistent/landmarks.yaml")

    def test_unreadable_initial_state_is_reported(self):
        self.check("ekf_slam_node", "/nonexistent/lab.state", "_initial_state:=/nonexistent/lab.state")
        # One saved map or the other, not both.
        self.check("ekf_slam_node", "initial_state", "_initial_state:=/tmp/lab.state",
                   "_initial_map:=/tmp/lab.yaml")

    def test_a_bad_start_pose_names_the_key(self):
        self.check("ekf_slam_node", "initial_cov_xx", "_initial_cov_xx:=-1.0")
        self.check("ekf_slam_node", "initial_pose_a", "_initial_pose_a:=100.0")

    def test_a_broken_grid_beside_initial_map_is_reported(self):
        folder = tempfile.mkdtemp(prefix="ekf_slam_initial_map_")
        path = write_map_set(folder)
        with open(os.path.join(folder, "lab_grid.pgm"), "wb") as f:
            f.write(b"P5\n4 3\n255\n\x00")  # cut short
        self.check("ekf_slam_node", "lab_grid", "_initial_map:=" + path)

    def test_the_grid_beside_initial_map_goes_on_map(self):
        import rospy
        from nav_msgs.msg import MapMetaData, OccupancyGrid
        folder = tempfile.mkdtemp(prefix="ekf_slam_initial_map_")
        path = write_map_set(folder)
        rospy.init_node("initial_map_check", anonymous=True)
        received = {}
        rospy.Subscriber("map", OccupancyGrid, lambda m: received.setdefault("map", m))
        rospy.Subscriber("map_metadata", MapMetaData, lambda m: received.setdefault("info", m))
        node = subprocess.Popen(["rosrun", "ekf_slam", "ekf_slam_node", "__name:=initial_map_node",
                                 "_initial_map:=" + path, "_localize_only:=true",
                                 "_initial_pose_x:=1.0", "_initial_cov_xx:=0.25"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            deadline = time.time() + 30.0
            while len(received) < 2 and time.time() < deadline and node.poll() is None:
                time.sleep(0.1)
        finally:
            node.send_signal(signal.SIGINT)  # a clean shutdown flushes the log
            output = node.communicate(timeout=30)[0]
        self.assertIn("map", received, "no grid on map:\n" + output)
        grid = received["map"]
        self.assertEqual((grid.info.width, grid.info.height), (4, 3))
        self.assertAlmostEqual(grid.info.resolution, 0.1, places=6)
        self.assertAlmostEqual(grid.info.origin.position.x, -1.0)
        self.assertAlmostEqual(grid.info.origin.position.y, 2.0)
        # The image's top row is the grid's last (map_server's convention).
        self.assertEqual(list(grid.data), GRID_VALUES)
        self.assertEqual(received["info"].width, 4)
        self.assertIn("starts at (1.000 m", output)


# A 4 x 3 grid at 0.1 m, origin (-1, 2): its PGM rows top to bottom, and the
# nav_msgs values map_server gives them (bottom row first): 0 (black) is
# occupied, 254 free, 205 unknown.
PGM_ROWS = [[0, 254, 205, 254], [254, 254, 254, 0], [205, 205, 0, 254]]
GRID_VALUES = [-1, -1, 100, 0, 0, 0, 0, 100, 100, 0, -1, 0]


def write_map_set(folder):
    """A map set as ~save_map writes it (one landmark, a grid); returns the
    landmark file's path."""
    path = os.path.join(folder, "lab.yaml")
    with open(path, "w") as f:
        f.write("version: 2\nframe: map\ncount: 1\nlandmarks:\n"
                "  - {id: 3, x: 0.5, y: 2.1, covariance: [0.0004, 0.0, 0.0, 0.0004], "
                "observations: 7}\nlines: []\nline_angles: []\n")
    with open(os.path.join(folder, "lab_grid.pgm"), "wb") as f:
        f.write(b"P5\n4 3\n255\n" + bytes(v for row in PGM_ROWS for v in row))
    with open(os.path.join(folder, "lab_grid.yaml"), "w") as f:
        f.write("image: lab_grid.pgm\nresolution: 0.1\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return path

    # The drivers read their parameters with the same reader: a wrong type
    # is an error, not a silent default.
    def test_lms200_node_wrong_type_names_the_key(self):
        self.check("lms200_node", "baud", "_baud:=fast", "_port:=/dev/null")

    def test_lms200_node_unknown_key(self):
        self.check("lms200_node", "time_ofset", "_time_ofset:=0.1", "_port:=/dev/null")

    def test_p3dx_driver_out_of_range_names_the_key(self):
        self.check("p3dx_driver_node", "max_linear_velocity", "_max_linear_velocity:=5.0",
                   "_port:=/dev/null")

    def test_feature_node_unknown_key(self):
        self.check("feature_node", "scan_topc", "_scan_topc:=scan")


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "slam_node_params", BadParameters)
