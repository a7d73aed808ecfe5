#!/usr/bin/python3
"""Supervised step mode (thesis §3.4.3) on the simulated robot with SLAM
(test/step_mode.test):

- teleop.py with step_mode, typed into a real pseudo-terminal, pauses SLAM;
  each key is one bounded move, and SLAM iterates once after each, with the
  robot at rest: one pose per step, none while moving;
- after ten steps the SLAM pose agrees with the truth;
- a 2 m drive made while SLAM is paused (more than the filter's 1 m jump
  bound) is kept: ~step afterwards puts the robot where it is.
"""
import math
import threading
import time
import unittest

import rospy
import rostest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped, Twist
from nav_msgs.msg import Odometry
from std_srvs.srv import Trigger

from ekf_slam_tools.se2 import compose, inverse, wrap, yaw_of
from ekf_slam_tools.terminal import TerminalProgram, wait_for

KEYS = "wawdwsawdw"  # ten steps: forward, turns both ways, one backward; heading kept


class Recorder:
    def __init__(self):
        self.lock = threading.Lock()
        self.truth = []  # (monotonic, (x, y, yaw) world, speed, stamp)
        self.poses = []  # (monotonic, (x, y, yaw) map, stamp: the scan's)
        self.slam = {}
        rospy.Subscriber("ground_truth/odom", Odometry, self.on_truth, queue_size=500)
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=100)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)

    def on_truth(self, message):
        p = message.pose.pose
        speed = abs(message.twist.twist.linear.x) + abs(message.twist.twist.angular.z)
        with self.lock:
            self.truth.append((time.monotonic(),
                               (p.position.x, p.position.y, yaw_of(p.orientation)), speed,
                               message.header.stamp.to_sec()))

    def on_pose(self, message):
        p = message.pose.pose
        with self.lock:
            self.poses.append((time.monotonic(),
                               (p.position.x, p.position.y, yaw_of(p.orientation)),
                               message.header.stamp.to_sec()))

    def on_diagnostics(self, message):
        for status in message.status:
            if status.name.endswith("EKF-SLAM"):
                with self.lock:
                    self.slam = {kv.key: kv.value for kv in status.values}

    def truth_now(self):
        with self.lock:
            return self.truth[-1][1]

    def moving_at(self, stamp, window=0.1):
        """The robot moved (ground truth) within `window` s of the ROS time `stamp`."""
        with self.lock:
            near = [s for _, _, s, st in self.truth if abs(st - stamp) <= window]
        return any(s > 0.01 for s in near)

    def moving_recently(self, seconds):
        now = time.monotonic()
        with self.lock:
            return any(s > 0.01 for t, _, s, _ in self.truth if t >= now - seconds)

    def poses_since(self, t):
        with self.lock:
            return [p for p in self.poses if p[0] >= t]


class StepMode(unittest.TestCase):
    def test_step_mode(self):
        rospy.init_node("step_mode_test")
        with open(rospy.get_param("~world_file")) as stream:
            to_map = inverse(tuple(yaml.safe_load(stream)["start_pose"]))
        r = Recorder()
        self.assertTrue(wait_for(lambda: len(r.poses) > 5 and r.truth, 60.0), "SLAM not running")

        teleop = TerminalProgram(["rosrun", "ekf_slam", "teleop.py", "__name:=teleop_steps",
                                  "_step_mode:=true", "_slam_namespace:=/ekf_slam"])
        try:
            self.assertTrue(teleop.wait_for_text("step mode", 30.0),
                            "no step-mode help: %r" % teleop.text())
            self.assertTrue(wait_for(lambda: r.slam.get("paused") == "True", 10.0),
                            "teleop did not pause SLAM")
            time.sleep(1.0)
            paused_at = time.monotonic()
            for n, key in enumerate(KEYS, start=1):
                rospy.loginfo("step_mode_test: key %s", key)
                teleop.type(key)
                self.assertTrue(teleop.wait_for_text("step %d:" % n, 20.0),
                                "step %d (%s) not done: %r" % (n, key, teleop.text()[-300:]))
            time.sleep(1.0)
            teleop.type("q")
            teleop.wait()
        finally:
            teleop.kill()
        steps = r.poses_since(paused_at)
        rospy.loginfo("step mode: %d SLAM poses over %d steps", len(steps), len(KEYS))
        self.assertEqual(len(steps), len(KEYS), "one iteration per step, none in between")
        for _, _, stamp in steps:
            self.assertFalse(r.moving_at(stamp), "an iteration on a scan taken while moving")
        truth = compose(to_map, r.truth_now())
        last = steps[-1][1]
        error = math.hypot(last[0] - truth[0], last[1] - truth[1])
        rospy.loginfo("after ten steps: SLAM (%.3f, %.3f, %.1f deg), truth (%.3f, %.3f, %.1f deg)",
                      last[0], last[1], math.degrees(last[2]), truth[0], truth[1],
                      math.degrees(truth[2]))
        self.assertLess(error, 0.10)
        self.assertLess(abs(wrap(last[2] - truth[2])), math.radians(3.0))

        # A 2 m drive while paused, then one step: kept, not a jump.
        start = r.truth_now()
        drive = rospy.Publisher("cmd_vel_in", Twist, queue_size=1)
        twist = Twist()
        twist.linear.x = 0.4
        deadline = time.monotonic() + 20.0
        while not rospy.is_shutdown() and time.monotonic() < deadline:
            now = r.truth_now()
            if math.hypot(now[0] - start[0], now[1] - start[1]) >= 2.0:
                break
            drive.publish(twist)
            time.sleep(0.1)
        drive.publish(Twist())
        now = r.truth_now()
        self.assertGreaterEqual(math.hypot(now[0] - start[0], now[1] - start[1]), 2.0,
                                "the robot could not drive 2 m")
        self.assertTrue(wait_for(lambda: not r.moving_recently(0.5), 10.0))
        before = time.monotonic()
        rospy.wait_for_service("/ekf_slam/step", 10.0)
        rospy.ServiceProxy("/ekf_slam/step", Trigger)()
        self.assertTrue(wait_for(lambda: r.poses_since(before), 10.0), "no iteration after ~step")
        after = r.poses_since(before)[0][1]
        truth = compose(to_map, r.truth_now())
        error = math.hypot(after[0] - truth[0], after[1] - truth[1])
        rospy.loginfo("after a 2 m paused drive: SLAM (%.3f, %.3f), truth (%.3f, %.3f)",
                      after[0], after[1], truth[0], truth[1])
        self.assertLess(error, 0.10, "the paused drive was not kept")
        self.assertTrue(wait_for(
            lambda: r.slam.get("large moves made while paused, kept") == "1", 10.0), r.slam)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "step_mode", StepMode)
