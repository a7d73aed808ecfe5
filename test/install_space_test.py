#!/usr/bin/python3
"""The package runs from its install space (test/install_space.test.in).

1. Installs the built workspace into its install space (`cmake --install`:
   what `catkin_make install` does after its build), emptied first.
2. In the development space (the test's own environment), `rosrun ekf_slam
   ekf_slam_offline --help` prints the help with no warning or prompt.
3. In a clean environment that sources only that install space:
   - `rospack find ekf_slam` is the installed share folder, and
     `rosrun ekf_slam ekf_slam_offline --help` prints the help;
   - offline.launch runs on a short bag (a robot circling in a box room,
     written here), and its results are complete: report, trajectories with
     finite numbers, the occupancy map and the figures (drawn by the
     installed plotting script);
   - sim.launch starts headless, on a master of its own, and the SLAM node
     publishes a pose within a minute;
   - a package built on ekf_slam (test/consumer) builds against the
     installed headers and libraries and runs (consumer_package_test.py).
"""
import math
import os
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

import rosbag
import rospy
import rostest
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan

from ekf_slam_tools.trajectories import read_rows
from consumer_package_test import build_and_run_consumer

# The room (m): walls of a box and a square pillar, as segments.
ROOM = [(-4.0, -3.0), (4.0, -3.0), (4.0, 3.0), (-4.0, 3.0)]
PILLAR = [(1.3, 0.8), (1.7, 0.8), (1.7, 1.2), (1.3, 1.2)]


def polygon_segments(corners):
    return [(corners[i], corners[(i + 1) % len(corners)]) for i in range(len(corners))]


SEGMENTS = polygon_segments(ROOM) + polygon_segments(PILLAR)


def cast(x, y, angle, max_range):
    """Distance from (x, y) along `angle` to the nearest segment."""
    dx, dy = math.cos(angle), math.sin(angle)
    best = max_range
    for (ax, ay), (bx, by) in SEGMENTS:
        ex, ey = bx - ax, by - ay
        denominator = dx * ey - dy * ex
        if abs(denominator) < 1e-12:
            continue
        t = ((ax - x) * ey - (ay - y) * ex) / denominator  # along the beam
        s = ((ax - x) * dy - (ay - y) * dx) / denominator  # along the segment
        if 0.0 < t < best and 0.0 <= s <= 1.0:
            best = t
    return best


def write_box_room_bag(path, seconds=30.0):
    """Scans at 5 Hz (181 beams, 1 deg) and odometry at 20 Hz of a robot
    driving a circle of radius 1.5 m; laser at base_link."""
    speed, turn_rate = 0.3, 0.2
    start = 1000.0
    with rosbag.Bag(path, "w") as bag:
        for k in range(int(seconds * 20) + 1):
            t = k / 20.0
            heading = turn_rate * t
            x = -0.5 + speed / turn_rate * math.sin(heading)
            y = -2.0 + speed / turn_rate * (1.0 - math.cos(heading))
            stamp = rospy.Time.from_sec(start + t)
            odom = Odometry()
            odom.header.stamp = stamp
            odom.header.frame_id = "odom"
            odom.child_frame_id = "base_link"
            odom.pose.pose.position.x = x
            odom.pose.pose.position.y = y
            odom.pose.pose.orientation.z = math.sin(heading / 2.0)
            odom.pose.pose.orientation.w = math.cos(heading / 2.0)
            bag.write("/odom", odom, stamp)
            if k % 4 == 0:
                scan = LaserScan()
                scan.header.stamp = stamp
                scan.header.frame_id = "base_link"
                scan.angle_min = -math.pi / 2.0
                scan.angle_max = math.pi / 2.0
                scan.angle_increment = math.pi / 180.0
                scan.range_min = 0.1
                scan.range_max = 8.0
                scan.ranges = [cast(x, y, heading + scan.angle_min + i * scan.angle_increment, 8.0)
                               for i in range(181)]
                bag.write("/scan", scan, stamp)


class InstallSpace(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.build_dir = rospy.get_param("~build_dir")
        # catkin writes the install space's setup files to the prefix the
        # workspace was configured with, so that is where it goes.
        cls.prefix = rospy.get_param("~install_dir")
        cls.work = tempfile.mkdtemp(prefix="ekf_slam_install_")
        shutil.rmtree(cls.prefix, ignore_errors=True)
        run = subprocess.run(["cmake", "--install", cls.build_dir],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             universal_newlines=True)
        if run.returncode != 0:
            raise AssertionError("install failed:\n" + run.stdout[-3000:])

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def clean_run(self, command, timeout, port=None, background=False):
        """`command` (a shell line) with only the install space sourced."""
        env = {"HOME": os.environ.get("HOME", "/tmp"), "PATH": "/usr/bin:/bin",
               "ROS_HOME": os.path.join(self.work, "ros_home"), "LANG": "C.UTF-8"}
        if port is not None:
            env["ROS_MASTER_URI"] = "http://localhost:%d" % port
        line = "source '%s/setup.bash' && %s" % (self.prefix, command)
        if background:
            return subprocess.Popen(["bash", "-c", line], env=env, stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, universal_newlines=True,
                                    start_new_session=True)
        return subprocess.run(["bash", "-c", line], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, universal_newlines=True, timeout=timeout,
                              stdin=subprocess.DEVNULL)

    def test_0_rosrun_finds_one_program_in_the_development_space(self):
        # The workspaces (also those of make bench and make benchmark) live
        # outside the source tree: rosrun sees one copy, and no loop.
        run = subprocess.run(["rosrun", "ekf_slam", "ekf_slam_offline", "--help"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             stdin=subprocess.DEVNULL, universal_newlines=True, timeout=60)
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
        self.assertIn("usage: ekf_slam_offline", run.stdout)
        self.assertEqual(run.stderr, "", "rosrun warned: " + run.stderr)

    def test_1_package_and_programs_are_found_in_the_install_space(self):
        run = self.clean_run("rospack find ekf_slam", 30)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertEqual(run.stdout.strip(), os.path.join(self.prefix, "share", "ekf_slam"))
        run = self.clean_run("rosrun ekf_slam ekf_slam_offline --help", 30)
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
        self.assertIn("usage: ekf_slam_offline", run.stdout)
        self.assertEqual(run.stderr, "", "rosrun warned: " + run.stderr)
        for name in ["ekf_slam_node", "feature_node", "ekf_slam_offline", "plot_offline.py",
                     "simulator_node", "p3dx_driver_node", "lms200_node", "waypoint_driver"]:
            path = os.path.join(self.prefix, "lib", "ekf_slam", name)
            self.assertTrue(os.access(path, os.X_OK), path + " not installed")

    def test_2_offline_launch_on_a_short_bag(self):
        bag = os.path.join(self.work, "box_room.bag")
        out = os.path.join(self.work, "offline_out")
        write_box_room_bag(bag)
        run = self.clean_run("roslaunch -p 11611 ekf_slam offline.launch bag:=%s out:=%s"
                             % (bag, out), 300)
        self.assertEqual(run.returncode, 0, run.stdout[-3000:] + run.stderr[-3000:])
        self.assertTrue(os.path.exists(os.path.join(out, "report.txt")), run.stdout[-3000:])
        for name in ["trajectory_filtered.txt", "trajectory_smoothed.txt", "trajectory_live.txt"]:
            rows = read_rows(os.path.join(out, name))
            self.assertGreater(len(rows), 100, name)
            for row in rows:
                self.assertTrue(all(math.isfinite(v) for v in row), name + ": " + str(row))
        for name in ["map.pgm", "map.yaml", "landmarks.yaml"]:
            self.assertGreater(os.path.getsize(os.path.join(out, name)), 0, name)
        figures = sorted(f for f in os.listdir(out) if f.endswith(".png"))
        self.assertEqual(figures, ["fig_first_last_scans.png", "fig_map_slam_vs_odometry.png",
                                   "fig_smoothing.png"],
                         "the installed plotting script did not draw every figure\n"
                         + run.stderr[-2000:])

    def test_3_sim_launch_starts_headless(self):
        port = 11612
        launch = self.clean_run("exec roslaunch -p %d ekf_slam sim.launch link_dir:=%s"
                                % (port, os.path.join(self.work, "pty")), None, port=port,
                                background=True)
        try:
            deadline = time.time() + 90.0
            pose = None
            while time.time() < deadline and launch.poll() is None:
                try:
                    pose = self.clean_run("rostopic echo -n 1 /pose", 20, port=port)
                except subprocess.TimeoutExpired:
                    continue
                if pose.returncode == 0 and "position" in pose.stdout:
                    break
                time.sleep(1.0)
            self.assertIsNone(launch.poll(), "sim.launch exited early")
            self.assertIsNotNone(pose, "no pose published within 90 s")
            self.assertIn("position", pose.stdout, pose.stdout + pose.stderr)
        finally:
            os.killpg(launch.pid, signal.SIGINT)
            try:
                launch.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(launch.pid, signal.SIGKILL)
                launch.wait()

    def test_4_a_package_builds_on_the_installed_core(self):
        ok, text = build_and_run_consumer(os.path.join(self.prefix, "setup.bash"),
                                          os.path.join(self.work, "consumer_ws"))
        print(text)
        self.assertTrue(ok, text)


if __name__ == "__main__":
    rospy.init_node("install_space_test")
    rostest.rosrun("ekf_slam", "install_space", InstallSpace)
