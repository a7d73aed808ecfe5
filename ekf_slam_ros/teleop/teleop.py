#!/usr/bin/python3
"""teleop: drive the robot from the keyboard of the terminal it runs in, or
from a joystick, by publishing geometry_msgs/Twist on cmd_vel_in (the
safety gate's input; docs/bringup.md).

    rosrun ekf_slam teleop.py                         # keyboard, in a terminal of its own
    rosrun ekf_slam teleop.py _joy_device:=/dev/input/js0
    roslaunch ekf_slam robot.launch joystick:=/dev/input/js0

Keyboard (help on screen): w / s faster forward / backward, a / d turn more
to the left / right, space stops, q quits. The arrow keys work as w a s d.
Joystick: sensor_msgs/Joy on `joy` from any joystick driver, or a Linux
joystick device read directly (`~joy_device`). The stick axes scale
`~max_linear` and `~max_angular`; motion only while the enable button
(dead man) is held, unless `~joy_enable_button` is -1.

A non-zero command is re-sent at `~rate`; once stopped, a zero is sent for
half a second and then nothing, so that another driver (the waypoint
driver) can use cmd_vel_in and the P3-DX's own watchdog stays in charge.
The command stops when the joystick falls silent for `~joy_timeout`.
"""
import os
import select
import struct
import sys
import termios
import threading
import time
import tty

import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import Joy

HELP = """\
teleop: keys act in this terminal
  w / up arrow      faster forward (or slower backward)
  s / down arrow    slower forward (or faster backward)
  a / left arrow    turn more to the left
  d / right arrow   turn more to the right
  space             stop
  q / Ctrl-C        stop and quit
"""

KEYS = {"w": (1, 0), "s": (-1, 0), "a": (0, 1), "d": (0, -1),
        "\x1b[A": (1, 0), "\x1b[B": (-1, 0), "\x1b[D": (0, 1), "\x1b[C": (0, -1)}

JS_EVENT = struct.Struct("<IhBB")  # time (ms), value, type, number: linux/joystick.h
JS_BUTTON, JS_AXIS, JS_INIT = 0x01, 0x02, 0x80
STOP_REPEAT = 0.5  # s of zero commands after a stop


def clamp(value, limit):
    return max(-limit, min(limit, value))


class Teleop:
    def __init__(self):
        get = rospy.get_param
        self.max_linear = float(get("~max_linear", 0.4))       # m/s
        self.max_angular = float(get("~max_angular", 0.8))     # rad/s
        self.linear_step = float(get("~linear_step", 0.05))    # m/s per key press
        self.angular_step = float(get("~angular_step", 0.1))   # rad/s per key press
        self.rate = float(get("~rate", 10.0))                  # Hz
        self.joy_linear_axis = int(get("~joy_linear_axis", 1))
        self.joy_angular_axis = int(get("~joy_angular_axis", 0))
        self.joy_enable_button = int(get("~joy_enable_button", 4))
        self.joy_timeout = float(get("~joy_timeout", 0.5))     # s
        self.joy_device = str(get("~joy_device", ""))
        problems = [name for name, value in (("max_linear", self.max_linear),
                                             ("max_angular", self.max_angular),
                                             ("linear_step", self.linear_step),
                                             ("angular_step", self.angular_step),
                                             ("rate", self.rate),
                                             ("joy_timeout", self.joy_timeout))
                    if not value > 0.0]
        if problems:
            raise ValueError("parameters must be > 0: " + ", ".join(
                rospy.resolve_name("~" + name) for name in problems))
        self.lock = threading.Lock()
        self.linear = self.angular = 0.0
        self.stopped_at = time.monotonic()
        self.joy_active = False
        self.joy_seen = 0.0
        self.publisher = rospy.Publisher("cmd_vel_in", Twist, queue_size=1)
        rospy.Subscriber("joy", Joy, self.on_joy, queue_size=5)

    # Commands ---------------------------------------------------------
    def set(self, linear, angular):
        with self.lock:
            linear, angular = clamp(linear, self.max_linear), clamp(angular, self.max_angular)
            if (linear, angular) == (0.0, 0.0) and (self.linear, self.angular) != (0.0, 0.0):
                self.stopped_at = time.monotonic()
            self.linear, self.angular = linear, angular

    def key(self, name):
        if name == " ":
            self.set(0.0, 0.0)
            return
        step = KEYS.get(name)
        if step is None:
            return
        with self.lock:
            linear = round((self.linear + step[0] * self.linear_step) / self.linear_step)
            angular = round((self.angular + step[1] * self.angular_step) / self.angular_step)
        self.set(linear * self.linear_step, angular * self.angular_step)

    def on_joy(self, message):
        axes, buttons = message.axes, message.buttons
        enabled = self.joy_enable_button < 0 or (
            self.joy_enable_button < len(buttons) and buttons[self.joy_enable_button] == 1)
        self.joy_seen = time.monotonic()
        if enabled:
            self.joy_active = True
            linear = axes[self.joy_linear_axis] if self.joy_linear_axis < len(axes) else 0.0
            angular = axes[self.joy_angular_axis] if self.joy_angular_axis < len(axes) else 0.0
            self.set(linear * self.max_linear, angular * self.max_angular)
        elif self.joy_active:  # dead man released
            self.joy_active = False
            self.set(0.0, 0.0)

    def tick(self):
        """Sends the command due now; called at `rate`."""
        if self.joy_active and time.monotonic() - self.joy_seen > self.joy_timeout:
            rospy.logwarn("teleop: the joystick fell silent for %.1f s: stop", self.joy_timeout)
            self.joy_active = False
            self.set(0.0, 0.0)
        with self.lock:
            moving = (self.linear, self.angular) != (0.0, 0.0)
            if not moving and time.monotonic() - self.stopped_at > STOP_REPEAT:
                return
            twist = Twist()
            twist.linear.x, twist.angular.z = self.linear, self.angular
        self.publisher.publish(twist)

    def status(self):
        with self.lock:
            return "v %+.2f m/s, w %+.2f rad/s" % (self.linear, self.angular)

    # Joystick device ------------------------------------------------------
    def read_joystick_device(self):
        """Reads js_event records from a Linux joystick device into Joy
        messages, as the ROS joy driver would publish them (axes in [-1, 1],
        pushed forward or to the left positive)."""
        axes, buttons = [0.0] * 8, [0] * 16
        try:
            device = open(self.joy_device, "rb", buffering=0)
        except OSError as error:
            rospy.logerr("teleop: cannot open the joystick %s: %s", self.joy_device, error)
            return
        with device:
            while not rospy.is_shutdown():
                data = device.read(JS_EVENT.size)
                if len(data) < JS_EVENT.size:
                    rospy.logwarn("teleop: the joystick %s closed: stop", self.joy_device)
                    self.joy_active = False
                    self.set(0.0, 0.0)
                    return
                _, value, kind, number = JS_EVENT.unpack(data)
                kind &= ~JS_INIT
                if kind == JS_AXIS and number < len(axes):
                    axes[number] = -value / 32767.0
                elif kind == JS_BUTTON and number < len(buttons):
                    buttons[number] = 1 if value else 0
                else:
                    continue
                message = Joy()
                message.header.stamp = rospy.Time.now()
                message.axes, message.buttons = list(axes), list(buttons)
                self.on_joy(message)


def read_key(stream):
    """One key press from a terminal in cbreak mode: a character or an arrow
    key's escape sequence; None when nothing is waiting."""
    ready, _, _ = select.select([stream], [], [], 0.0)
    if not ready:
        return None
    first = os.read(stream.fileno(), 1).decode("latin-1")
    if first != "\x1b":
        return first
    rest = ""
    while len(rest) < 2 and select.select([stream], [], [], 0.05)[0]:
        rest += os.read(stream.fileno(), 1).decode("latin-1")
    return first + rest


def main():
    rospy.init_node("teleop", disable_signals=True)
    try:
        teleop = Teleop()
    except ValueError as error:
        rospy.logfatal("teleop: %s", error)
        return 1
    if teleop.joy_device:
        threading.Thread(target=teleop.read_joystick_device, daemon=True).start()
    keyboard = sys.stdin.isatty()
    saved = None
    if keyboard:
        saved = termios.tcgetattr(sys.stdin)
        tty.setcbreak(sys.stdin.fileno())
        sys.stdout.write(HELP)
        sys.stdout.flush()
    elif not teleop.joy_device:
        rospy.loginfo("teleop: stdin is not a terminal: joystick on 'joy' only")
    period = 1.0 / teleop.rate
    shown = None
    try:
        while not rospy.is_shutdown():
            began = time.monotonic()
            while keyboard:
                name = read_key(sys.stdin)
                if name is None:
                    break
                if name in ("q", "\x03"):
                    raise KeyboardInterrupt
                teleop.key(name)
            teleop.tick()
            if keyboard and teleop.status() != shown:
                shown = teleop.status()
                sys.stdout.write("\r" + shown + "   ")
                sys.stdout.flush()
            time.sleep(max(0.0, period - (time.monotonic() - began)))
    except KeyboardInterrupt:
        pass
    finally:
        teleop.set(0.0, 0.0)
        teleop.publisher.publish(Twist())
        if saved is not None:
            termios.tcsetattr(sys.stdin, termios.TCSADRAIN, saved)
            sys.stdout.write("\nteleop: stopped\n")
        time.sleep(0.1)
        rospy.signal_shutdown("teleop quit")
    return 0


if __name__ == "__main__":
    sys.exit(main())
