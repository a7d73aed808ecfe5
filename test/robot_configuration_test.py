#!/usr/bin/python3
"""The robot's configuration files, run for real (test/robot_configuration.test).

- p3dx_description turns config/p3dx.urdf and a calibration file into a
  description that check_urdf accepts, with the laser joint at the
  calibration's mount and the 16 sonar frames of the driver;
- robot_state_publisher, given that description, broadcasts base_link ->
  laser as the calibration says;
- robot.launch starts robot_state_publisher (and no second publisher of the
  mount);
- record.launch records the scans, the odometry and the static frames into
  a bag that ekf_slam_offline reads.
"""
import glob
import math
import os
import shutil
import signal
import subprocess
import tempfile
import time
import unittest
import xml.etree.ElementTree as ElementTree

import rosbag
import rospkg
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import Quaternion, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage

PACKAGE = rospkg.RosPack().get_path("ekf_slam")

CALIBRATION = """parent_frame: base_link
child_frame: laser
x: 0.213
y: -0.031
z: 0.25
yaw: 0.0524
"""


def yaw_quaternion(yaw):
    return Quaternion(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def description(calibration_path):
    return subprocess.run(["rosrun", "ekf_slam", "p3dx_description.py", calibration_path],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True)


class RobotConfiguration(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("robot_configuration_test")
        cls.tmp = tempfile.mkdtemp(prefix="robot_configuration_")
        cls.calibration = os.path.join(cls.tmp, "calibration.yaml")
        with open(cls.calibration, "w") as stream:
            stream.write(CALIBRATION)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def check_urdf(self, path):
        run = subprocess.run(["check_urdf", path], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, universal_newlines=True)
        self.assertEqual(run.returncode, 0, run.stdout)
        self.assertIn("root Link: base_link", run.stdout)

    def test_shipped_urdf_loads(self):
        self.check_urdf(os.path.join(PACKAGE, "config", "p3dx.urdf"))

    def test_description_carries_the_calibration(self):
        run = description(self.calibration)
        self.assertEqual(run.returncode, 0, run.stderr)
        path = os.path.join(self.tmp, "p3dx.urdf")
        with open(path, "w") as stream:
            stream.write(run.stdout)
        self.check_urdf(path)
        robot = ElementTree.fromstring(run.stdout)
        origin = robot.find("joint[@name='laser_joint']/origin")
        xyz = [float(v) for v in origin.get("xyz").split()]
        rpy = [float(v) for v in origin.get("rpy").split()]
        self.assertEqual(xyz, [0.213, -0.031, 0.25])
        self.assertEqual(rpy, [0.0, 0.0, 0.0524])
        sonars = {link.get("name") for link in robot.findall("link")
                  if link.get("name").startswith("sonar_")}
        self.assertEqual(sonars, {"sonar_%d" % i for i in range(16)})
        # A tilted mount: roll and pitch go to the joint too (URDF's rpy).
        tilted = os.path.join(self.tmp, "tilted.yaml")
        with open(tilted, "w") as stream:
            stream.write(CALIBRATION + "roll: 0.01\npitch: -0.0349\n")
        run = description(tilted)
        self.assertEqual(run.returncode, 0, run.stderr)
        origin = ElementTree.fromstring(run.stdout).find("joint[@name='laser_joint']/origin")
        self.assertEqual([float(v) for v in origin.get("rpy").split()], [0.01, -0.0349, 0.0524])

    def test_bad_calibration_is_refused_with_the_key(self):
        path = os.path.join(self.tmp, "bad.yaml")
        with open(path, "w") as stream:
            stream.write(CALIBRATION.replace("yaw: 0.0524", "yaw: .nan"))
        run = description(path)
        self.assertEqual(run.returncode, 1)
        self.assertIn("yaw: must be a finite number", run.stderr)
        with open(path, "w") as stream:
            stream.write(CALIBRATION.replace("parent_frame: base_link", "parent_frame: chassis"))
        run = description(path)
        self.assertEqual(run.returncode, 1)
        self.assertIn("parent_frame 'chassis'", run.stderr)

    def test_robot_state_publisher_broadcasts_the_mount(self):
        rospy.set_param("/robot_description", description(self.calibration).stdout)
        publisher = subprocess.Popen(["rosrun", "robot_state_publisher", "robot_state_publisher"])
        try:
            buffer = tf2_ros.Buffer()
            tf2_ros.TransformListener(buffer)
            mount = buffer.lookup_transform("base_link", "laser", rospy.Time(0),
                                            rospy.Duration(30.0))
            self.assertAlmostEqual(mount.transform.translation.x, 0.213, places=6)
            self.assertAlmostEqual(mount.transform.translation.y, -0.031, places=6)
            q = mount.transform.rotation
            yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
            self.assertAlmostEqual(yaw, 0.0524, places=6)
            sonar = buffer.lookup_transform("base_link", "sonar_11", rospy.Time(0),
                                            rospy.Duration(5.0))
            self.assertAlmostEqual(sonar.transform.translation.x, -0.255, places=6)
        finally:
            publisher.send_signal(signal.SIGINT)
            publisher.wait(timeout=20)

    def test_robot_launch_runs_robot_state_publisher(self):
        run = subprocess.run(["roslaunch", "--nodes", os.path.join(PACKAGE, "launch", "robot.launch")],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             universal_newlines=True)
        self.assertEqual(run.returncode, 0, run.stdout)
        nodes = run.stdout.split()
        self.assertIn("/robot_state_publisher", nodes)
        self.assertNotIn("/calibration_tf_publisher", nodes)
        # SLAM on the robot: the built-in defaults with the P3-DX's odometry noise.
        run = subprocess.run(["roslaunch", "--dump-params",
                              os.path.join(PACKAGE, "launch", "robot.launch")],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             universal_newlines=True)
        self.assertEqual(run.returncode, 0, run.stdout)
        self.assertIn("ekf_slam_p3dx.yaml", run.stdout)
        printed = subprocess.run(["rosrun", "ekf_slam", "ekf_slam_offline", "--config",
                                  os.path.join(PACKAGE, "config", "ekf_slam_p3dx.yaml"),
                                  "--print-config"], stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, universal_newlines=True)
        self.assertEqual(printed.returncode, 0, printed.stdout)
        values = dict(line.split(": ", 1) for line in printed.stdout.splitlines() if ": " in line)
        self.assertAlmostEqual(float(values["filter.motion_noise.rot_per_rot"]), 0.0203)
        self.assertAlmostEqual(float(values["filter.motion_noise.trans_per_trans"]), 0.0267)

    def test_record_launch_records_what_offline_reads(self):
        prefix = os.path.join(self.tmp, "run")
        record = subprocess.Popen(["roslaunch", "ekf_slam", "record.launch", "prefix:=" + prefix],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        scan_pub = rospy.Publisher("/scan", LaserScan, queue_size=10)
        odom_pub = rospy.Publisher("/odom", Odometry, queue_size=10)
        tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=10)
        static_pub = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        # Frames of its own: the test's latched /tf_static must not reach the
        # other tests' tf listeners as base_link -> laser.
        mount = TransformStamped()
        mount.header.frame_id = "recorded_base_link"
        mount.child_frame_id = "recorded_laser"
        mount.transform.translation.x = 0.16
        mount.transform.rotation = yaw_quaternion(0.0)
        static_pub.publish(TFMessage([mount]))
        try:
            deadline = time.monotonic() + 30.0
            sent = 0
            while time.monotonic() < deadline and sent < 40:
                if scan_pub.get_num_connections() == 0:  # rosbag not subscribed yet
                    time.sleep(0.1)
                    continue
                stamp = rospy.Time.now()
                scan = LaserScan()
                scan.header.stamp = stamp
                scan.header.frame_id = "recorded_laser"
                scan.angle_min, scan.angle_max = -math.pi / 2, math.pi / 2
                scan.angle_increment = math.pi / 180
                scan.range_max = 80.0
                scan.ranges = [2.0] * 181
                odom = Odometry()
                odom.header.stamp = stamp
                odom.header.frame_id = "recorded_odom"
                odom.child_frame_id = "recorded_base_link"
                odom.pose.pose.position.x = 0.01 * sent
                odom.pose.pose.orientation = yaw_quaternion(0.0)
                motion = TransformStamped()
                motion.header = odom.header
                motion.child_frame_id = "recorded_base_link"
                motion.transform.translation.x = 0.01 * sent
                motion.transform.rotation = yaw_quaternion(0.0)
                scan_pub.publish(scan)
                odom_pub.publish(odom)
                tf_pub.publish(TFMessage([motion]))
                sent += 1
                time.sleep(0.05)
            self.assertEqual(sent, 40, "rosbag record never subscribed to /scan")
            time.sleep(1.0)
        finally:
            record.send_signal(signal.SIGINT)
            record.wait(timeout=30)
            for publisher in (scan_pub, odom_pub, tf_pub, static_pub):
                publisher.unregister()
        bags = glob.glob(prefix + "_*.bag")
        self.assertEqual(len(bags), 1, "bags: %s" % os.listdir(self.tmp))
        counts = {}
        with rosbag.Bag(bags[0]) as bag:
            for topic, _, _ in bag.read_messages():
                counts[topic] = counts.get(topic, 0) + 1
        for topic in ("/scan", "/odom", "/tf"):
            self.assertGreaterEqual(counts.get(topic, 0), 30, "%s: %s" % (topic, counts))
        self.assertGreaterEqual(counts.get("/tf_static", 0), 1, counts)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "robot_configuration", RobotConfiguration)
