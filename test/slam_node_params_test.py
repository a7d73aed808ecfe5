#!/usr/bin/python3
"""The nodes refuse bad parameters at start-up.

ekf_slam_node and feature_node, the two drivers (p3dx_driver_node,
lms200_node) and simulator_node, which share the same parameter reader.

Each case starts the node with one bad private parameter (or a bad
configuration file) against the rostest roscore and asserts that it exits
with code 1 and that its error names the offending key.
"""
import os
import subprocess
import tempfile
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
