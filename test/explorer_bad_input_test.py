#!/usr/bin/python3
"""explorer_node on bad input (test/explorer_bad_input.test): the node alone,
the robot's pose published here on /tf (map -> odom -> base_link, at rest
at the origin) and the map drawn here on /map.

- An empty map (every cell unknown): nothing is reachable; the robot is
  held at rest and the reason is an ERROR on /diagnostics.
- A robot enclosed in a small walled box: the same, "enclosed".
- A map with a way out: the explorer drives (a forward command on
  cmd_vel); ~pause stops it and ~resume lets it drive again.
- The map stops arriving: after ~map_timeout the robot is stopped and the
  reason ("no new map ... the newest map is too old") is on /diagnostics; a new map lets
  it drive on.
- ~abort: the robot is stopped for good; a later map does not move it.
- A second explorer (namespace budget, its map on budget_map) with a 4 s
  time budget ends
  exploring when it is spent, returns to its start (it stands there) and
  finishes: ~done true, "the time budget is spent" on /diagnostics.
"""
import sys
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TransformStamped, Twist
from nav_msgs.msg import OccupancyGrid
from std_msgs.msg import Bool
from std_srvs.srv import Trigger

RESOLUTION = 0.05


def grid(rows):
    """An OccupancyGrid from text rows, top row first: '#' occupied, '.'
    free, '?' unknown; the map origin (the robot) at the grid's centre."""
    message = OccupancyGrid()
    message.header.frame_id = "map"
    message.info.resolution = RESOLUTION
    message.info.height = len(rows)
    message.info.width = len(rows[0])
    message.info.origin.position.x = -0.5 * len(rows[0]) * RESOLUTION
    message.info.origin.position.y = -0.5 * len(rows) * RESOLUTION
    message.info.origin.orientation.w = 1.0
    values = {"#": 100, ".": 0, "?": -1}
    for row in reversed(rows):
        message.data.extend(values[c] for c in row)
    return message


def empty_map():
    return grid(["?" * 80] * 80)


def enclosed_map():
    rows = ["?" * 80] * 80
    rows = [list(r) for r in rows]
    for r in range(30, 50):  # a 1 m box of wall around free cells
        for c in range(30, 50):
            edge = r in (30, 49) or c in (30, 49)
            rows[r][c] = "#" if edge else "."
    return grid(["".join(r) for r in rows])


def open_map():
    """Free space 2 m around the robot, unknown beyond: frontiers on all sides."""
    rows = []
    for r in range(120):
        rows.append("".join("." if 20 <= r < 100 and 20 <= c < 100 else "?" for c in range(120)))
    return grid(rows)


class Watcher:
    def __init__(self):
        self.lock = threading.Lock()
        self.commands = []  # (monotonic, linear, angular)
        self.status = None
        self.budget_status = None
        self.budget_done = False
        rospy.Subscriber("budget/explorer/done", Bool, self.on_budget_done, queue_size=1)
        rospy.Subscriber("cmd_vel", Twist, self.on_cmd, queue_size=100)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=20)
        self.map_publisher = rospy.Publisher("map", OccupancyGrid, queue_size=1, latch=True)
        self.budget_map_publisher = rospy.Publisher("budget_map", OccupancyGrid, queue_size=1,
                                                    latch=True)
        self.tf = tf2_ros.TransformBroadcaster()
        self.pose_thread = threading.Thread(target=self.publish_pose, daemon=True)
        self.pose_thread.start()

    def publish_pose(self):
        rate = rospy.Rate(20)
        while not rospy.is_shutdown():
            # REP-105: map -> odom (SLAM) -> base_link (odometry).
            stamp = rospy.Time.now()
            transforms = []
            for parent, child in (("map", "odom"), ("odom", "base_link")):
                t = TransformStamped()
                t.header.stamp = stamp
                t.header.frame_id = parent
                t.child_frame_id = child
                t.transform.rotation.w = 1.0
                transforms.append(t)
            self.tf.sendTransform(transforms)
            rate.sleep()

    def on_cmd(self, message):
        with self.lock:
            self.commands.append((time.monotonic(), message.linear.x, message.angular.z))

    def on_budget_done(self, message):
        self.budget_done = self.budget_done or message.data

    def on_diagnostics(self, message):
        for status in message.status:
            if not status.name.endswith("exploration"):
                continue
            with self.lock:
                if "budget" in status.name:
                    self.budget_status = (status.level, status.message)
                else:
                    self.status = (status.level, status.message)

    def moving_since(self, since):
        with self.lock:
            return [c for c in self.commands if c[0] >= since and (c[1] != 0.0 or c[2] != 0.0)]

    def last_command_since(self, since):
        with self.lock:
            recent = [c for c in self.commands if c[0] >= since]
        return recent[-1] if recent else None

    def wait_status(self, level, text, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not rospy.is_shutdown():
            with self.lock:
                status = self.status
            if status and status[0] == level and text in status[1]:
                return status
            time.sleep(0.1)
        return self.status

    def wait_moving(self, since, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not rospy.is_shutdown():
            if self.moving_since(since):
                return True
            time.sleep(0.1)
        return False


def call(name):
    rospy.wait_for_service(name, timeout=10.0)
    return rospy.ServiceProxy(name, Trigger)()


class ExplorerBadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("explorer_bad_input_test")
        cls.w = Watcher()

    def test_bad_input_in_turn(self):
        w = self.w
        # An empty map.
        start = time.monotonic()
        w.map_publisher.publish(empty_map())
        status = w.wait_status(DiagnosticStatus.ERROR, "nothing is reachable", 20.0)
        self.assertEqual(status[0], DiagnosticStatus.ERROR, status)
        self.assertIn("empty map", status[1])
        self.assertFalse(w.moving_since(start), "the robot was told to move on an empty map")

        # The robot enclosed in a box.
        start = time.monotonic()
        w.map_publisher.publish(enclosed_map())
        status = w.wait_status(DiagnosticStatus.ERROR, "enclosed", 10.0)
        self.assertIn("enclosed", status[1], status)
        self.assertFalse(w.moving_since(start), "the robot was told to move inside the box")

        # A way out: it drives; pause holds it, resume drives again.
        start = time.monotonic()
        w.map_publisher.publish(open_map())
        self.assertTrue(w.wait_moving(start, 10.0), "no motion with frontiers around the robot")
        self.assertTrue(call("explorer/pause").success)
        time.sleep(0.5)
        paused = time.monotonic()
        time.sleep(1.5)
        self.assertFalse(w.moving_since(paused), "moving while paused")
        self.assertTrue(call("explorer/resume").success)
        self.assertTrue(w.wait_moving(time.monotonic(), 10.0), "no motion after resume")

        # The map stops arriving (map_timeout 3 s in the .test; the open map
        # above is latched but not re-sent).
        status = w.wait_status(DiagnosticStatus.WARN, "too old", 15.0)
        self.assertIn("no new map on /map for longer than map_timeout", status[1], status)
        time.sleep(0.5)
        stopped = time.monotonic()
        time.sleep(1.0)
        self.assertFalse(w.moving_since(stopped), "moving on a stale map")
        last = w.last_command_since(stopped - 1.0)
        self.assertTrue(last is None or (last[1] == 0.0 and last[2] == 0.0), last)
        start = time.monotonic()
        w.map_publisher.publish(open_map())
        self.assertTrue(w.wait_moving(start, 10.0), "no motion once the map returned")

        # Abort: stopped for good.
        self.assertTrue(call("explorer/abort").success)
        time.sleep(0.5)
        aborted = time.monotonic()
        w.map_publisher.publish(open_map())
        time.sleep(3.0)
        self.assertFalse(w.moving_since(aborted), "moving after abort")
        self.assertFalse(call("explorer/resume").success)

    def test_a_time_budget_ends_exploring(self):
        w = self.w
        w.budget_map_publisher.publish(open_map())
        deadline = time.monotonic() + 30.0
        while not w.budget_done and time.monotonic() < deadline:
            time.sleep(0.2)
        self.assertTrue(w.budget_done, "the budgeted explorer did not finish: %s" %
                        (w.budget_status,))
        time.sleep(1.5)  # its next /diagnostics
        self.assertIn("the time budget is spent", w.budget_status[1], w.budget_status)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "explorer_bad_input", ExplorerBadInput, sys.argv)
