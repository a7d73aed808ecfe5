#!/usr/bin/python3
"""teleop.py through a real pseudo-terminal and a joystick device (test/teleop.test)."""
import os
import shutil
import signal
import struct
import subprocess
import tempfile
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from sensor_msgs.msg import Joy

from ekf_slam_tools.terminal import TerminalProgram, wait_for

JS_EVENT = struct.Struct("<IhBB")


class Commands:
    def __init__(self):
        self.lock = threading.Lock()
        self.received = []  # (monotonic, linear, angular)
        rospy.Subscriber("cmd_vel_in", Twist, self.on_twist, queue_size=100)

    def on_twist(self, message):
        with self.lock:
            self.received.append((time.monotonic(), message.linear.x, message.angular.z))

    def last(self):
        with self.lock:
            return self.received[-1][1:] if self.received else None

    def since(self, t):
        with self.lock:
            return [r for r in self.received if r[0] >= t]



def close(a, b):
    return a is not None and abs(a[0] - b[0]) < 1e-6 and abs(a[1] - b[1]) < 1e-6


class TeleopTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("teleop_test")
        cls.commands = Commands()
        cls.tmp = tempfile.mkdtemp(prefix="teleop_test_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_keyboard_in_a_terminal(self):
        teleop = TerminalProgram(["rosrun", "ekf_slam", "teleop.py", "__name:=teleop_keys",
                                  "_max_linear:=0.3", "_linear_step:=0.05",
                                  "_angular_step:=0.1"])
        try:
            self.assertTrue(teleop.wait_for_text("space             stop", 30.0),
                            "no help on screen: %r" % teleop.text())
            time.sleep(1.0)  # the subscriber connects
            teleop.type("www")
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.15, 0.0))),
                            "after w w w: %s" % (self.commands.last(),))
            teleop.type("\x1b[D")  # left arrow
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.15, 0.1))),
                            "after the left arrow: %s" % (self.commands.last(),))
            teleop.type("w" * 10)  # beyond max_linear: clamped
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.3, 0.1))),
                            "clamped: %s" % (self.commands.last(),))
            self.assertTrue(teleop.wait_for_text("v +0.30 m/s, w +0.10 rad/s", 10.0),
                            "status line: %r" % teleop.text()[-200:])
            teleop.type(" ")
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.0, 0.0))))
            time.sleep(1.0)  # zeros for half a second, then silence
            quiet_since = time.monotonic()
            time.sleep(1.0)
            self.assertEqual(self.commands.since(quiet_since), [], "still publishing when stopped")
            # A Joy message with the dead man held drives too.
            joy = rospy.Publisher("joy", Joy, queue_size=1)
            self.assertTrue(wait_for(lambda: joy.get_num_connections() > 0))
            started = time.monotonic()
            joy.publish(Joy(axes=[0.0, 0.5], buttons=[0, 0, 0, 0, 1]))
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.15, 0.0))),
                            "after Joy: %s" % (self.commands.last(),))
            # The joystick falls silent: stop within joy_timeout.
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.0, 0.0)), 3.0))
            self.assertLess(time.monotonic() - started, 2.0)
            teleop.type("q")
            self.assertTrue(teleop.wait_for_text("teleop: stopped", 10.0))
            self.assertEqual(teleop.wait(), 0)
        finally:
            teleop.kill()

    def test_joystick_device(self):
        fifo = os.path.join(self.tmp, "js0")
        os.mkfifo(fifo)
        teleop = subprocess.Popen(["rosrun", "ekf_slam", "teleop.py", "__name:=teleop_joy",
                                   "_joy_device:=" + fifo, "_max_linear:=0.3",
                                   "_max_angular:=0.8"], stdin=subprocess.DEVNULL)
        try:
            device = os.open(fifo, os.O_WRONLY)  # waits for teleop to open it
            time.sleep(1.0)  # the subscriber connects

            def event(value, kind, number):
                os.write(device, JS_EVENT.pack(0, value, kind, number))

            event(0, 0x82, 0)  # initial state of the axes and the dead man
            event(0, 0x82, 1)
            event(0, 0x81, 4)
            event(-32767, 0x02, 1)  # stick fully forward, dead man not held
            time.sleep(0.5)
            self.assertFalse(self.commands.since(time.monotonic() - 0.4), "moved without dead man")
            event(1, 0x01, 4)  # dead man held
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.3, 0.0))),
                            "stick forward: %s" % (self.commands.last(),))
            event(16384, 0x02, 0)  # half right
            self.assertTrue(wait_for(lambda: abs(self.commands.last()[1] + 0.4) < 1e-3),
                            "half right: %s" % (self.commands.last(),))
            event(0, 0x01, 4)  # dead man released
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.0, 0.0))))
            event(1, 0x01, 4)
            self.assertTrue(wait_for(lambda: self.commands.last()[0] > 0.2))
            os.close(device)  # unplugged: stop
            self.assertTrue(wait_for(lambda: close(self.commands.last(), (0.0, 0.0))))
        finally:
            teleop.send_signal(signal.SIGINT)
            try:
                teleop.wait(timeout=10)
            except subprocess.TimeoutExpired:
                teleop.kill()


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "teleop", TeleopTest)
