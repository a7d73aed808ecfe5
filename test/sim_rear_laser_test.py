#!/usr/bin/python3
"""The simulated robot with a rear LMS200 and SLAM merging it (test/sim_rear_laser.test).

Checks, on a real roscore with real pseudo-terminals:
  - base_link -> laser_rear is on /tf_static at the mount of
    config/calibration_rear.yaml (behind the axle, facing backwards);
  - scan_rear arrives from the second lms200_node in frame laser_rear with
    181 beams, and its ranges match a ray cast through the world grid from
    the true rear laser pose (truth at the scan stamp composed with the
    rear mount), so the emulator really looks backwards from there;
  - while the robot turns and drives a little (cmd_vel_in, through the
    safety gate), ekf_slam_node merges rear scans into its scans
    (/diagnostics: merged scans, no rear scan refused), the filter sees
    landmarks behind the robot (association reports in base_link with
    bearings beyond 100 degrees), the MECP association matches a polygon
    round the robot to one it remembered (MECP group matches > 0: the
    landmarks now enclose the robot), and the SLAM pose stays near the
    true pose.
"""
import math
import threading
import time
import unittest

import rospy
import rostest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from ekf_slam.msg import AssociationReport
from geometry_msgs.msg import PoseWithCovarianceStamped, Twist
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import LaserScan

from ekf_slam_tools.grids import range_errors
from ekf_slam_tools.messages import decode
from ekf_slam_tools.se2 import compose, interpolate, inverse, wrap, yaw_of
from ekf_slam_tools.terminal import wait_for

EXPECTED_BEAMS = 181  # 180 deg at 1 deg (config/lms200.yaml)


class Listener:
    def __init__(self):
        self.lock = threading.Lock()
        self.rear_scans = []
        self.truth = []  # (stamp s, (x, y, yaw)) in the world
        self.poses = []  # (stamp s, (x, y, yaw)) in map
        self.behind = 0  # matched observations behind the robot
        self.association_frames = set()
        self.slam = {}
        self.world = None
        self.static = {}
        rospy.Subscriber("scan_rear", LaserScan, self.on_rear_scan, queue_size=50)
        rospy.Subscriber("ground_truth/odom", Odometry, self.on_truth, queue_size=200)
        rospy.Subscriber("ground_truth/world", OccupancyGrid, self.on_world, queue_size=1)
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=50)
        rospy.Subscriber("association", AssociationReport, self.on_association, queue_size=50)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)
        # tf2_msgs has no Python package on Debian: the type is built from the
        # definition the publisher sends with the connection (as rosbag does).
        rospy.Subscriber("/tf_static", rospy.AnyMsg, self.on_static, queue_size=10)

    def on_rear_scan(self, message):
        with self.lock:
            self.rear_scans.append(message)

    def on_truth(self, message):
        pose = message.pose.pose
        with self.lock:
            self.truth.append((message.header.stamp.to_sec(),
                               (pose.position.x, pose.position.y, yaw_of(pose.orientation))))

    def on_world(self, message):
        self.world = message

    def on_pose(self, message):
        pose = message.pose.pose
        with self.lock:
            self.poses.append((message.header.stamp.to_sec(),
                               (pose.position.x, pose.position.y, yaw_of(pose.orientation))))

    def on_association(self, message):
        with self.lock:
            self.association_frames.add(message.header.frame_id)
            self.behind += sum(1 for o in message.observations
                               if o.decision == "matched" and abs(o.bearing) > math.radians(100))

    def on_diagnostics(self, message):
        for status in message.status:
            if status.name.endswith("EKF-SLAM"):
                with self.lock:
                    self.slam = {kv.key: kv.value for kv in status.values}

    def on_static(self, raw):
        for transform in decode(raw).transforms:
            self.static[(transform.header.frame_id, transform.child_frame_id)] = transform

    def counter(self, key):
        with self.lock:
            value = self.slam.get(key)
        return int(value) if value is not None else None

    def truth_at(self, stamp):
        """World pose at `stamp`, interpolated; None outside the history."""
        with self.lock:
            track = [(t,) + tuple(pose) for t, pose in self.truth]
        return interpolate(track, stamp)


class SimRearLaserTest(unittest.TestCase):
    def test_rear_laser_merged_into_slam(self):
        rospy.init_node("sim_rear_laser_test")
        listener = Listener()
        with open(rospy.get_param("~world_file")) as f:
            start = tuple(yaml.safe_load(f)["start_pose"])
        with open(rospy.get_param("~calibration_file")) as f:
            mount_file = yaml.safe_load(f)
        mount = (mount_file["x"], mount_file["y"], mount_file["yaw"])
        self.assertLess(mount[0], 0.0, "the rear laser sits behind the axle")

        # The rear mount on /tf_static, as the file says.
        self.assertTrue(wait_for(lambda: ("base_link", "laser_rear") in listener.static, 30.0),
                        "no base_link -> laser_rear on /tf_static")
        t = listener.static[("base_link", "laser_rear")].transform
        self.assertAlmostEqual(t.translation.x, mount[0], places=6)
        self.assertAlmostEqual(t.translation.y, mount[1], places=6)
        self.assertAlmostEqual(abs(wrap(yaw_of(t.rotation))), math.pi, places=6)

        # SLAM runs on merged scans before the robot moves.
        self.assertTrue(wait_for(lambda: len(listener.poses) > 5, 60.0),
                        "no pose from ekf_slam_node")
        self.assertTrue(wait_for(lambda: (listener.counter("scans merged with a rear scan") or 0)
                                 > 0, 30.0),
                        "no scan merged with a rear scan: %r" % listener.slam)

        # Turn and drive a little through the safety gate.
        cmd_vel = rospy.Publisher("cmd_vel_in", Twist, queue_size=1)
        for linear, angular, seconds in ((0.0, 0.4, 4.0), (0.2, 0.0, 3.0), (0.0, -0.4, 4.0)):
            twist = Twist()
            twist.linear.x, twist.angular.z = linear, angular
            deadline = time.monotonic() + seconds
            while time.monotonic() < deadline and not rospy.is_shutdown():
                cmd_vel.publish(twist)
                time.sleep(0.1)
        cmd_vel.publish(Twist())
        time.sleep(2.0)  # the last scans through SLAM, another diagnostics report

        # The rear scans: their own frame, and the world seen backwards from
        # the rear mount.
        with listener.lock:
            scans = list(listener.rear_scans)
        self.assertGreater(len(scans), 20, "too few scans on scan_rear")
        for scan in scans:
            self.assertEqual(scan.header.frame_id, "laser_rear")
            self.assertEqual(len(scan.ranges), EXPECTED_BEAMS)
        grid = listener.world
        self.assertIsNotNone(grid, "no ground_truth/world")
        checked = 0
        for scan in scans[-40::10]:  # 4 scans, the robot moving
            truth = listener.truth_at(scan.header.stamp.to_sec())
            if truth is None:
                continue
            laser = compose(compose(inverse(start), truth), mount)
            errors = range_errors(grid, laser, scan)
            self.assertGreater(len(errors), 100, "most rear beams hit something in this room")
            median, p90 = errors[len(errors) // 2], errors[int(0.9 * len(errors))]
            rospy.loginfo("rear scan vs ray cast from the truth: median %.3f m, 90%% %.3f m",
                          median, p90)
            self.assertLess(median, 0.03)
            self.assertLess(p90, 0.08)
            checked += 1
        self.assertGreaterEqual(checked, 3, "rear scan stamps must fall inside the truth history")

        # The node merged, the filter saw landmarks behind the robot, and
        # the MECP association matched polygons round the robot.
        merged = listener.counter("scans merged with a rear scan")
        alone = ((listener.counter("scans without the rear laser: none within "
                                   "rear_scan_tolerance") or 0)
                 + (listener.counter("scans without the rear laser: rear transforms missing")
                    or 0))
        mecp = listener.counter("MECP group matches")
        rospy.loginfo("merged %s scans, %d without the rear laser; MECP polygons %s, group "
                      "matches %s; %d matches behind the robot; counters %r", merged, alone,
                      listener.slam.get("MECP polygons"), mecp, listener.behind, listener.slam)
        self.assertGreater(merged, 20)
        self.assertEqual(listener.counter("rear scans refused"), 0)
        self.assertEqual(listener.association_frames, {"base_link"},
                         "observations of the merged scan are in base_link")
        self.assertGreater(listener.behind, 0, "no landmark matched behind the robot")
        self.assertIsNotNone(mecp, "MECP counters missing on /diagnostics: %r" % listener.slam)
        self.assertGreater(mecp, 0, "no polygon round the robot was ever matched again")

        # The estimate is still right: the last pose against the truth at
        # its stamp, both in the map frame (the start pose).
        with listener.lock:
            stamp, pose = listener.poses[-1]
        truth = listener.truth_at(stamp)
        self.assertIsNotNone(truth)
        truth = compose(inverse(start), truth)
        error = math.hypot(pose[0] - truth[0], pose[1] - truth[1])
        heading = abs(wrap(pose[2] - truth[2]))
        rospy.loginfo("last SLAM pose (%.3f, %.3f, %.1f deg), truth (%.3f, %.3f, %.1f deg)",
                      pose[0], pose[1], math.degrees(pose[2]), truth[0], truth[1],
                      math.degrees(truth[2]))
        self.assertLess(error, 0.15)
        self.assertLess(heading, math.radians(5.0))


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "sim_rear_laser", SimRearLaserTest)
