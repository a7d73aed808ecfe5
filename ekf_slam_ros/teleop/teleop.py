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

Supervised step mode (`~step_mode:=true`, the thesis's §3.4.3): SLAM is
paused (`~slam_namespace`/pause) and each key press is one bounded move:
w / s drive `~step_distance` forward / backward, a / d turn by
`~step_angle`, measured on the odometry (`odom`). When the robot has come
to rest, teleop calls `~slam_namespace`/step: SLAM runs one iteration on
the next scan and pauses again. The next key is taken once SLAM's pose of
that iteration has arrived (`pose`, 3 s at most), so that every iteration
sees the robot at rest; keys pressed meanwhile are ignored. A move the
safety gate cuts short ends after twice its time at the step speed plus
2 s, and is iterated all the same.
"""
import os
import select
import struct
import sys
import termios
import threading
import time
import tty

import math

import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped, Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Joy
from std_srvs.srv import Trigger

STEP_HELP = """\
teleop, supervised step mode: SLAM iterates once after each move
  w / s    one step forward / backward
  a / d    one turn to the left / right
  q        quit (SLAM stays paused: call its resume service)
"""

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
REST_TIME = 0.4    # s without odometry change: the robot is at rest (SIPs come every 0.1 s)


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
        self.step_mode = bool(get("~step_mode", False))
        self.step_distance = float(get("~step_distance", 0.25))  # m per step
        self.step_angle = float(get("~step_angle", math.radians(15.0)))  # rad per turn
        self.step_speed = float(get("~step_speed", 0.2))          # m/s while stepping
        self.step_turn_rate = float(get("~step_turn_rate", 0.4))  # rad/s while stepping
        self.slam_namespace = str(get("~slam_namespace", "/ekf_slam"))
        problems = [name for name, value in (("max_linear", self.max_linear),
                                             ("max_angular", self.max_angular),
                                             ("linear_step", self.linear_step),
                                             ("angular_step", self.angular_step),
                                             ("rate", self.rate),
                                             ("joy_timeout", self.joy_timeout),
                                             ("step_distance", self.step_distance),
                                             ("step_angle", self.step_angle),
                                             ("step_speed", self.step_speed),
                                             ("step_turn_rate", self.step_turn_rate))
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
        if self.step_mode:
            self.odometry = None  # (x, y, yaw)
            self.odometry_history = []  # (monotonic, (x, y, yaw)) over the last moments
            self.move = None      # the step under way
            self.steps = 0
            self.slam_missing = False  # SLAM's services did not answer
            self.slam_poses = 0   # SLAM poses received: one per iteration
            rospy.Subscriber("odom", Odometry, self.on_odometry, queue_size=5)
            rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_slam_pose, queue_size=5)

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

    # Supervised step mode ---------------------------------------------------
    def on_odometry(self, message):
        p, q = message.pose.pose.position, message.pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        now = time.monotonic()
        with self.lock:
            self.odometry = (p.x, p.y, yaw)
            self.odometry_history.append((now, self.odometry))
            while self.odometry_history and self.odometry_history[0][0] < now - REST_TIME - 0.2:
                self.odometry_history.pop(0)

    def at_rest(self):
        """The odometry pose has not changed (1 mm, 0.1°) over the last REST_TIME s."""
        now = time.monotonic()
        with self.lock:
            recent = [pose for t, pose in self.odometry_history if t >= now - REST_TIME]
            spans = bool(self.odometry_history) and self.odometry_history[0][0] <= now - REST_TIME
        if not spans or len(recent) < 2:
            return False
        return all(math.hypot(p[0] - recent[-1][0], p[1] - recent[-1][1]) < 0.001 and
                   abs(math.atan2(math.sin(p[2] - recent[-1][2]),
                                  math.cos(p[2] - recent[-1][2]))) < 0.002 for p in recent)

    def on_slam_pose(self, _):
        with self.lock:
            self.slam_poses += 1

    def call_slam(self, name):
        """Calls SLAM's Trigger service `name`; None when SLAM does not
        answer. Once it has not, later calls wait 0.2 s instead of 5 s: the
        steps go on without SLAM (driving only) and say so."""
        service = self.slam_namespace.rstrip("/") + "/" + name
        try:
            rospy.wait_for_service(service, timeout=0.2 if self.slam_missing else 5.0)
            answer = rospy.ServiceProxy(service, Trigger)()
            self.slam_missing = False
            return answer.message
        except (rospy.ROSException, rospy.ServiceException) as error:
            if not self.slam_missing:
                rospy.logwarn("teleop: %s failed (%s): stepping without SLAM", service, error)
            self.slam_missing = True
            return None

    def step_key(self, name):
        """Starts one bounded move for a key, unless one is under way."""
        step = KEYS.get(name)
        if step is None:
            return
        with self.lock:
            if self.move is not None:
                return  # one move at a time
            if self.odometry is None:
                rospy.logwarn_throttle(2.0, "teleop: no odometry on 'odom' yet: cannot step")
                return
            start = self.odometry
        if step[0] != 0:
            speed, target = step[0] * self.step_speed, self.step_distance
            expected = self.step_distance / self.step_speed
        else:
            speed, target = step[1] * self.step_turn_rate, self.step_angle
            expected = self.step_angle / self.step_turn_rate
        with self.lock:
            self.move = {"linear": step[0] != 0, "speed": speed, "target": target,
                         "start": start, "began": time.monotonic(),
                         "deadline": time.monotonic() + 2.0 * expected + 2.0, "stopping": None}

    def step_tick(self):
        """Drives the move under way; at rest, one SLAM iteration."""
        with self.lock:
            move, now_odometry = self.move, self.odometry
        if move is None or now_odometry is None:
            return
        x0, y0, yaw0 = move["start"]
        x, y, yaw = now_odometry
        done = (math.hypot(x - x0, y - y0) if move["linear"]
                else abs(math.atan2(math.sin(yaw - yaw0), math.cos(yaw - yaw0))))
        now = time.monotonic()
        if move["stopping"] is None:
            if done < move["target"] and now < move["deadline"]:
                twist = Twist()
                if move["linear"]:
                    twist.linear.x = move["speed"]
                else:
                    twist.angular.z = move["speed"]
                self.publisher.publish(twist)
                return
            self.publisher.publish(Twist())
            move["stopping"] = now
            if done < move["target"]:
                rospy.logwarn("teleop: step cut short at %.3f of %.3f (safety gate or stall)",
                              done, move["target"])
            return
        if "iterating" in move:
            # The next key waits for SLAM's iteration (its pose), so that it
            # always sees the robot at rest; 3 s at most.
            with self.lock:
                iterated = self.slam_poses > move["poses_before"]
            if iterated or now - move["iterating"] > 3.0:
                unit = "m" if move["linear"] else "rad"
                sys.stdout.write("\rstep %d: moved %.3f %s; SLAM %s\n" % (
                    self.steps, move["done"], unit,
                    "iterated" if iterated else "did not iterate within 3 s"))
                sys.stdout.flush()
                with self.lock:
                    self.move = None
            return
        # At rest: the odometry still for REST_TIME (or 4 s at most).
        self.publisher.publish(Twist())
        if self.at_rest() or now - move["stopping"] > 4.0:
            with self.lock:
                move["poses_before"] = self.slam_poses
            if self.call_slam("step") is None:
                move["poses_before"] = -1  # no SLAM: do not wait for it
            self.steps += 1
            move["done"] = done
            move["iterating"] = time.monotonic()

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
    if teleop.step_mode:
        answer = teleop.call_slam("pause")
        rospy.loginfo("teleop: step mode; SLAM: %s", answer or "not reached")
    if keyboard:
        saved = termios.tcgetattr(sys.stdin)
        tty.setcbreak(sys.stdin.fileno())
        sys.stdout.write(STEP_HELP if teleop.step_mode else HELP)
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
                if teleop.step_mode:
                    teleop.step_key(name)
                else:
                    teleop.key(name)
            if teleop.step_mode:
                teleop.step_tick()
                time.sleep(max(0.0, period - (time.monotonic() - began)))
                continue
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
