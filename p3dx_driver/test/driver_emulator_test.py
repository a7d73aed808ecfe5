#!/usr/bin/python3
"""p3dx_driver_node against p3dx_emulator on a pseudo-terminal, through ROS.

Private parameter ~scenario selects the cases: "basic" (handshake, 1 m
square, cmd_vel timeout, unplug/replug) or "corruption" (5 % corrupted SIPs).
"""
import math
import subprocess
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Range
from std_msgs.msg import Bool
from std_srvs.srv import SetBool, Trigger

POSITION_TOLERANCE = 0.01  # m
ANGLE_TOLERANCE = math.radians(1.0)


def yaw_of(message):
    q = message.pose.pose.orientation
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(angle):
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class Listener:
    """Keeps the latest messages and the whole odom history."""

    def __init__(self):
        self.lock = threading.Lock()
        self.odom = []
        self.emulator_odometry = None
        self.motors_enabled = None
        self.stall = None
        self.sonar = None
        self.link_status = None
        rospy.Subscriber("odom", Odometry, self.on_odom, queue_size=100)
        rospy.Subscriber("p3dx_emulator/odometry", Odometry, self.on_emulator, queue_size=10)
        rospy.Subscriber("motors_enabled", Bool, self.on_motors, queue_size=1)
        rospy.Subscriber("stall", Bool, self.on_stall, queue_size=1)
        rospy.Subscriber("sonar/3", Range, self.on_sonar, queue_size=1)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=10)

    def on_odom(self, message):
        with self.lock:
            self.odom.append((time.monotonic(), message))

    def on_emulator(self, message):
        with self.lock:
            self.emulator_odometry = message

    def on_motors(self, message):
        self.motors_enabled = message.data

    def on_stall(self, message):
        self.stall = message.data

    def on_sonar(self, message):
        self.sonar = message

    def on_diagnostics(self, message):
        for status in message.status:
            if "P3-DX link" in status.name:
                with self.lock:
                    self.link_status = status

    def last_odom(self):
        with self.lock:
            return self.odom[-1] if self.odom else (None, None)

    def diagnostic_value(self, key):
        with self.lock:
            if self.link_status is None:
                return None
            for item in self.link_status.values:
                if item.key == key:
                    return item.value
        return None


def wait_for(condition, timeout, period=0.02):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not rospy.is_shutdown():
        if condition():
            return True
        time.sleep(period)
    return condition()


class DriverEmulatorTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("p3dx_driver_test")
        cls.listener = Listener()
        cls.cmd_vel = rospy.Publisher("cmd_vel", Twist, queue_size=10)

    def setUp(self):
        self.assertTrue(
            wait_for(lambda: self.listener.last_odom()[1] is not None, 30.0),
            "no odom from p3dx_driver_node within 30 s (handshake failed?)")
        self.assertTrue(wait_for(lambda: self.listener.emulator_odometry is not None, 10.0),
                        "no ~odometry from p3dx_emulator")

    def send(self, linear, angular):
        twist = Twist()
        twist.linear.x = linear
        twist.angular.z = angular
        self.cmd_vel.publish(twist)

    def drive_until(self, linear, angular, done, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not done():
            self.send(linear, angular)
            time.sleep(0.05)
        self.send(0.0, 0.0)
        self.assertTrue(done(), "motion goal not reached in %.0f s" % timeout)

    def wait_until_still(self):
        def still():
            emulator = self.listener.emulator_odometry
            _, odom = self.listener.last_odom()
            return (emulator.twist.twist.linear.x == 0.0 and emulator.twist.twist.angular.z == 0.0
                    and odom.twist.twist.linear.x == 0.0 and odom.twist.twist.angular.z == 0.0)
        self.assertTrue(wait_for(still, 10.0), "robot did not stop")
        time.sleep(0.3)  # one more SIP at rest

    def assert_odometry_matches_emulator(self, where):
        _, odom = self.listener.last_odom()
        emulator = self.listener.emulator_odometry
        dx = odom.pose.pose.position.x - emulator.pose.pose.position.x
        dy = odom.pose.pose.position.y - emulator.pose.pose.position.y
        dyaw = wrap(yaw_of(odom) - yaw_of(emulator))
        rospy.loginfo("%s: odometry vs emulator %.5f m, %.4f deg", where, math.hypot(dx, dy),
                      math.degrees(dyaw))
        self.assertLess(math.hypot(dx, dy), POSITION_TOLERANCE,
                        "%s: position differs by %.4f m" % (where, math.hypot(dx, dy)))
        self.assertLess(abs(dyaw), ANGLE_TOLERANCE,
                        "%s: heading differs by %.3f deg" % (where, math.degrees(dyaw)))


class BasicTest(DriverEmulatorTest):
    def test_1_handshake(self):
        self.assertTrue(wait_for(lambda: self.listener.motors_enabled is True, 10.0),
                        "motors_enabled never became true after the handshake")
        self.assertTrue(wait_for(lambda: self.listener.diagnostic_value("link state") == "connected",
                                 10.0), "diagnostics do not report a connected link")
        self.assertIn("p3dx", self.listener.diagnostic_value("robot"))

    def test_2_square(self):
        for side in range(4):
            _, start = self.listener.last_odom()
            x0, y0, yaw0 = start.pose.pose.position.x, start.pose.pose.position.y, yaw_of(start)

            def travelled():
                _, odom = self.listener.last_odom()
                return math.hypot(odom.pose.pose.position.x - x0,
                                  odom.pose.pose.position.y - y0) >= 0.95
            self.drive_until(0.5, 0.0, travelled, 15.0)
            self.wait_until_still()
            self.assert_odometry_matches_emulator("side %d" % side)

            def turned():
                _, odom = self.listener.last_odom()
                return wrap(yaw_of(odom) - yaw0) >= math.radians(85.0)
            self.drive_until(0.0, 1.0, turned, 15.0)
            self.wait_until_still()
            self.assert_odometry_matches_emulator("corner %d" % side)

    def test_3_cmd_vel_timeout_stops_robot(self):
        for _ in range(30):  # 1.5 s of commands, then silence
            self.send(0.3, 0.0)
            time.sleep(0.05)
        last_command = time.monotonic()
        self.assertGreater(self.listener.emulator_odometry.twist.twist.linear.x, 0.1)
        stopped = wait_for(lambda: self.listener.emulator_odometry.twist.twist.linear.x == 0.0, 5.0)
        elapsed = time.monotonic() - last_command
        self.assertTrue(stopped, "robot still moving 5 s after the last cmd_vel")
        rospy.loginfo("robot stopped %.2f s after the last cmd_vel", elapsed)
        # cmd_vel_timeout 0.5 s + deceleration 0.3 m/s at 1 m/s² + latency,
        # well before the robot's own 2 s watchdog.
        self.assertLess(elapsed, 1.5, "robot stopped only after %.2f s" % elapsed)

    def test_4_unplug_replug_reconnects(self):
        self.wait_until_still()
        _, before = self.listener.last_odom()
        set_connected = rospy.ServiceProxy("p3dx_emulator/set_connected", SetBool)
        set_connected(False)
        self.assertTrue(
            wait_for(lambda: self.listener.diagnostic_value("link state") == "disconnected", 5.0),
            "driver did not report the unplugged link")
        time.sleep(0.5)
        set_connected(True)
        replugged = time.monotonic()
        resumed = wait_for(lambda: self.listener.last_odom()[0] > replugged + 0.05, 10.0)
        delay = self.listener.last_odom()[0] - replugged
        self.assertTrue(resumed, "no odom after replug")
        self.assertLess(delay, 3.0, "reconnect took %.2f s" % delay)
        _, after = self.listener.last_odom()
        jump = math.hypot(after.pose.pose.position.x - before.pose.pose.position.x,
                          after.pose.pose.position.y - before.pose.pose.position.y)
        self.assertLess(jump, POSITION_TOLERANCE, "odometry jumped %.4f m on reconnect" % jump)
        self.assertLess(abs(wrap(yaw_of(after) - yaw_of(before))), ANGLE_TOLERANCE)
        rospy.loginfo("reconnected %.2f s after replug", delay)


    def test_5_unknown_parameter_is_rejected_by_name(self):
        result = subprocess.run(
            ["rosrun", "ekf_slam", "p3dx_driver_node", "__name:=p3dx_bad_config",
             "_port:=/tmp/p3dx_no_such_port", "_cmd_vel_timeuot:=1.0"],
            capture_output=True, text=True, timeout=30)
        self.assertNotEqual(result.returncode, 0, "a misspelt parameter was accepted")
        self.assertIn("cmd_vel_timeuot", result.stdout + result.stderr)


    def test_6_stall_is_reported(self):
        set_stalled = rospy.ServiceProxy("p3dx_emulator/set_stalled", SetBool)
        set_stalled(True)
        try:
            # Keep pushing against the blocked wheels while diagnostics (1 Hz) catch up.
            deadline = time.monotonic() + 5.0
            while time.monotonic() < deadline and not (
                    self.listener.stall and self.listener.diagnostic_value("stalled") == "True"):
                self.send(0.2, 0.0)
                time.sleep(0.05)
            self.send(0.0, 0.0)
            self.assertTrue(self.listener.stall, "stall not published while the wheels are blocked")
            self.assertEqual(self.listener.diagnostic_value("stalled"), "True",
                             "diagnostics do not show the stall")
        finally:
            set_stalled(False)
        self.wait_until_still()
        self.assertTrue(wait_for(lambda: self.listener.stall is False, 5.0))

    def test_7_motor_and_odometry_services(self):
        enable = rospy.ServiceProxy("p3dx_driver/enable_motors", SetBool)
        self.assertTrue(enable(False).success)
        self.assertTrue(wait_for(lambda: self.listener.motors_enabled is False, 5.0),
                        "motors_enabled did not become false")
        self.assertTrue(enable(True).success)
        self.assertTrue(wait_for(lambda: self.listener.motors_enabled is True, 5.0))
        _, odom = self.listener.last_odom()
        self.assertGreater(abs(odom.pose.pose.position.x) + abs(odom.pose.pose.position.y), 0.1)
        reset = rospy.ServiceProxy("p3dx_driver/reset_odometry", Trigger)
        self.assertTrue(reset().success)
        called = time.monotonic()
        self.assertTrue(wait_for(lambda: self.listener.last_odom()[0] > called + 0.05, 5.0))
        _, odom = self.listener.last_odom()
        self.assertLess(math.hypot(odom.pose.pose.position.x, odom.pose.pose.position.y), 1e-3)
        self.assertLess(abs(yaw_of(odom)), 1e-3)


class CorruptionTest(DriverEmulatorTest):
    def test_corrupt_packets_counted_and_skipped(self):
        first = len(self.listener.odom)
        deadline = time.monotonic() + 8.0
        while time.monotonic() < deadline:
            self.send(0.4, 0.3)
            time.sleep(0.05)
        self.send(0.0, 0.0)
        self.wait_until_still()
        with self.listener.lock:
            history = self.listener.odom[first:]
        self.assertGreater(len(history), 50)
        for (t0, a), (t1, b) in zip(history, history[1:]):
            step = math.hypot(b.pose.pose.position.x - a.pose.pose.position.x,
                              b.pose.pose.position.y - a.pose.pose.position.y)
            dt = (b.header.stamp - a.header.stamp).to_sec()
            self.assertLess(step, 0.4 * dt + 0.05, "odometry jump of %.3f m in %.3f s" % (step, dt))
        self.assert_odometry_matches_emulator("after driving with corruption")
        time.sleep(1.5)  # next diagnostics cycle
        errors = int(self.listener.diagnostic_value("checksum errors"))
        packets = int(self.listener.diagnostic_value("packets"))
        rospy.loginfo("checksum errors %d of %d packets", errors, packets)
        self.assertGreater(errors, 0, "no checksum error counted at a 5 % corruption rate")
        self.assertLess(errors, 0.15 * packets, "more errors counted than packets corrupted")
        # Sonar is on in this test: the emulator reports 5 m (its maximum).
        self.assertIsNotNone(self.listener.sonar, "no sonar/3 message")
        self.assertEqual(self.listener.sonar.header.frame_id, "sonar_3")
        self.assertTrue(math.isinf(self.listener.sonar.range))


if __name__ == "__main__":
    scenario = rospy.get_param("/p3dx_driver_test/scenario", "basic")
    case = {"basic": BasicTest, "corruption": CorruptionTest}[scenario]
    rostest.rosrun("ekf_slam", "p3dx_driver_" + scenario, case)
