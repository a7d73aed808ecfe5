#!/usr/bin/python3
"""The safety gate on the simulated robot (test/safety_stop.test,
test/safety_bumper.test): sim.launch without SLAM, the robot driven straight
at a wall through cmd_vel_in, as teleop or the waypoint driver would.

~mode laser (the default gate): the robot stops before it touches the wall
  (no stall, clearance above the body's radius), the gate reports the stop
  on /diagnostics, and backing away is allowed. The same again with the
  other drivers of the robot: teleop.py typed into a real pseudo-terminal,
  waypoint_driver given a goal beyond the wall, and teleop's step mode.
~mode bumper (the gate's laser check off): the robot reaches the wall, the
  emulated P3-DX presses its front bumper, and the gate refuses further
  forward motion (cmd_vel forward speed 0 while cmd_vel_in still asks for
  it) and reports it.
"""
import math
import os
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import rospy
import rostest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from nav_msgs.msg import OccupancyGrid, Odometry
from std_msgs.msg import Bool, UInt16

from ekf_slam_tools.grids import clearance
from ekf_slam_tools.se2 import compose, inverse, yaw_of
from ekf_slam_tools.terminal import TerminalProgram, wait_for

ROBOT_RADIUS = 0.26  # m, config/simulator.yaml: the disc that may not overlap a wall
SPEED = 0.4          # m/s, commanded


class Recorder:
    def __init__(self):
        self.lock = threading.Lock()
        self.truth = []      # (monotonic, (x, y, yaw)) in the world
        self.world = None
        self.stalled = False
        self.front_bumper = False
        self.sent = []       # linear speeds the gate sent to the driver
        self.gate = {}       # the gate's last /diagnostics values
        self.gate_message = ""
        rospy.Subscriber("ground_truth/odom", Odometry, self.on_truth, queue_size=200)
        rospy.Subscriber("ground_truth/world", OccupancyGrid, self.on_world, queue_size=1)
        rospy.Subscriber("stall", Bool, self.on_stall, queue_size=10)
        rospy.Subscriber("bumpers", UInt16, self.on_bumpers, queue_size=10)
        rospy.Subscriber("cmd_vel", Twist, self.on_cmd_vel, queue_size=50)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)

    def on_truth(self, message):
        p = message.pose.pose
        with self.lock:
            self.truth.append((time.monotonic(), (p.position.x, p.position.y, yaw_of(p.orientation))))

    def on_world(self, message):
        self.world = message

    def on_stall(self, message):
        self.stalled = self.stalled or message.data

    def on_bumpers(self, message):
        self.front_bumper = self.front_bumper or ((message.data >> 9) & 0x7F) != 0

    def on_cmd_vel(self, message):
        with self.lock:
            self.sent.append(message.linear.x)

    def on_diagnostics(self, message):
        for status in message.status:
            if status.name.endswith("safety gate"):
                with self.lock:
                    self.gate = {kv.key: kv.value for kv in status.values}
                    self.gate_message = status.message

    def pose(self):
        with self.lock:
            return self.truth[-1][1] if self.truth else None

    def moved_since(self, seconds):
        """Distance covered over the last `seconds` of ground truth."""
        now = time.monotonic()
        with self.lock:
            recent = [p for t, p in self.truth if t >= now - seconds]
        if len(recent) < 2:
            return float("inf")
        return math.hypot(recent[-1][0] - recent[0][0], recent[-1][1] - recent[0][1])


class SafetyStop(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("safety_stop_test")
        cls.mode = rospy.get_param("~mode", "laser")
        cls.recorder = Recorder()
        cls.command = rospy.Publisher("cmd_vel_in", Twist, queue_size=1)
        # ground_truth/world is drawn in the frame of the start pose.
        with open(rospy.get_param("~world_file")) as stream:
            cls.from_world = inverse(tuple(yaml.safe_load(stream)["start_pose"]))

    def drive(self, linear, seconds, until_still=False):
        """Publishes (linear, 0) on cmd_vel_in at 10 Hz for `seconds`, or until
        the robot has not moved for 2 s (after the first 3 s)."""
        twist = Twist()
        twist.linear.x = linear
        began = time.monotonic()
        while time.monotonic() - began < seconds and not rospy.is_shutdown():
            self.command.publish(twist)
            time.sleep(0.1)
            if (until_still and time.monotonic() - began > 3.0
                    and self.recorder.moved_since(2.0) < 0.005):
                return True
        return False

    def assert_stopped_clear(self, what, timeout=40.0):
        """The robot comes to rest short of the wall, untouched."""
        r = self.recorder
        began = time.monotonic()
        time.sleep(3.0)
        while time.monotonic() - began < timeout and r.moved_since(2.0) >= 0.005:
            time.sleep(0.2)
        end = r.pose()
        gap = clearance(r.world, compose(self.from_world, end), 2.0)
        rospy.loginfo("safety_stop (%s): stopped %.3f m from the wall", what, gap)
        self.assertLess(r.moved_since(2.0), 0.005, what + ": the robot never came to rest")
        self.assertFalse(r.stalled, what + ": the robot touched the wall (stall)")
        self.assertGreater(gap, ROBOT_RADIUS + 0.02, what + ": stopped touching the wall")

    def back_away(self):
        self.drive(-0.2, 2.5)
        self.command.publish(Twist())
        time.sleep(1.0)

    def teleop_at_the_wall(self):
        teleop = TerminalProgram(["rosrun", "ekf_slam", "teleop.py", "__name:=teleop_safety"])
        try:
            self.assertTrue(teleop.wait_for_text("space", 30.0), teleop.text())
            time.sleep(1.0)
            teleop.type("w" * 6)  # 0.3 m/s straight at the wall
            self.assert_stopped_clear("teleop")
            teleop.type("q")
            teleop.wait()
        finally:
            teleop.kill()

    def steps_at_the_wall(self):
        """Step mode (no SLAM here: its pause and step calls time out and
        the steps go on): 0.25 m steps at the wall until the gate cuts them
        short."""
        teleop = TerminalProgram(["rosrun", "ekf_slam", "teleop.py",
                                  "__name:=teleop_steps_safety", "_step_mode:=true"])
        try:
            self.assertTrue(teleop.wait_for_text("one step forward", 30.0), teleop.text())
            for n in range(1, 7):
                teleop.type("w")
                self.assertTrue(teleop.wait_for_text("step %d:" % n, 30.0), teleop.text())
            self.assert_stopped_clear("step mode")
            teleop.type("q")
            teleop.wait()
        finally:
            teleop.kill()

    def waypoints_through_the_wall(self):
        r = self.recorder
        odom = rospy.wait_for_message("odom", Odometry, timeout=10.0)
        p = odom.pose.pose
        x, y, yaw = p.position.x, p.position.y, yaw_of(p.orientation)
        path = os.path.join(tempfile.mkdtemp(prefix="safety_waypoints_"), "through_the_wall.yaml")
        with open(path, "w") as stream:
            stream.write("closed: false\nwaypoints:\n  - [%.3f, %.3f]\n" %
                         (x + 4.0 * math.cos(yaw), y + 4.0 * math.sin(yaw)))
        driver = subprocess.Popen(["rosrun", "ekf_slam", "waypoint_driver",
                                   "__name:=waypoints_safety", "cmd_vel:=cmd_vel_in",
                                   "_waypoints_file:=" + path, "_global_frame:=odom"])
        try:
            self.assert_stopped_clear("waypoint driver")
        finally:
            driver.send_signal(signal.SIGINT)
            driver.wait(timeout=20)
        self.assertFalse(r.front_bumper)

    def test_driven_at_a_wall(self):
        r = self.recorder
        self.assertTrue(wait_for(lambda: r.world is not None and r.pose() is not None, 30.0),
                        "no ground truth from the simulator")
        self.assertTrue(wait_for(lambda: self.command.get_num_connections() > 0, 30.0),
                        "safety_gate does not listen on cmd_vel_in")
        start = r.pose()
        stopped = self.drive(SPEED, 40.0, until_still=True)
        end = r.pose()
        travelled = math.hypot(end[0] - start[0], end[1] - start[1])
        gap = clearance(r.world, compose(self.from_world, end), 2.0)
        rospy.loginfo("safety_stop (%s): driven %.2f m, stopped %.3f m from the wall "
                      "(body radius %.2f m); gate: %s %s", self.mode, travelled, gap,
                      ROBOT_RADIUS, r.gate_message, r.gate)
        self.assertTrue(stopped, "the robot never came to rest")
        self.assertGreater(travelled, 0.5, "the robot hardly moved")
        with r.lock:
            sent_last = r.sent[-5:]
        self.assertTrue(sent_last and all(v == 0.0 for v in sent_last),
                        "the gate still sends forward speed: %s" % sent_last)
        self.assertTrue(wait_for(lambda: r.gate_message.startswith("limiting the robot"), 5.0),
                        "the stop is not on /diagnostics: %r" % r.gate_message)
        if self.mode == "laser":
            self.assertFalse(r.stalled, "the robot touched the wall (the driver reported a stall)")
            self.assertFalse(r.front_bumper, "the robot touched the wall (front bumper)")
            self.assertGreater(gap, ROBOT_RADIUS + 0.02, "stopped touching the wall")
            self.assertLess(gap, ROBOT_RADIUS + 0.6, "stopped far before the wall")
            self.assertIn("obstacle", r.gate_message)
            self.assertGreaterEqual(int(r.gate.get("stops: obstacle", "0")), 1)
        else:
            self.assertTrue(r.front_bumper, "the emulator never pressed the front bumper")
            self.assertLess(gap, ROBOT_RADIUS + 0.02, "it did not reach the wall")
            self.assertGreaterEqual(int(r.gate.get("stops: front bumper", "0")) +
                                    int(r.gate.get("stops: wheel stall", "0")), 1)
            self.assertGreaterEqual(int(r.gate.get("stops: front bumper", "0")), 1)
        # Backing away is allowed, then the gate clears.
        before = r.pose()
        self.drive(-0.2, 2.5)
        after = r.pose()
        self.assertGreater(math.hypot(after[0] - before[0], after[1] - before[1]), 0.15,
                           "the gate kept the robot from backing away")
        self.command.publish(Twist())
        if self.mode == "laser":  # the other drivers of the robot, the same wall
            time.sleep(1.0)
            self.teleop_at_the_wall()
            self.back_away()
            self.waypoints_through_the_wall()
            self.back_away()
            self.steps_at_the_wall()


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "safety_stop", SafetyStop)
