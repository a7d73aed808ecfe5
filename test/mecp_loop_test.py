#!/usr/bin/python3
"""MECP association closes a loop that nearest neighbour misses (test/mecp_loop.test).

On a real roscore, two ekf_slam_node instances (/nn: points with nearest
neighbour; /mecp: points+mecp) take the same ekf_slam/Features messages and
the same odom -> base_link transforms (the laser at base_link on
/tf_static), published here from a world built
for the purpose:
  - a room whose four corners lie about 4 m round its centre, seen (all
    round, as with a front and a rear laser) only from within 0.6 m of the
    centre: its walls hide them from the corridor;
  - the robot stands at the centre, drives 3 m out along the corridor,
    turns round, drives back and turns round again; in the first turn a
    wheel slips and the odometry reports 5 degrees less turn than the robot
    made (1.9 sigma of the configured turn noise);
  - four more features stand where that error carries the corners: on
    return each corner appears where the dead-reckoned pose expects one of
    them.
Nearest neighbour pairs the corners with those four and keeps the slip's
error (about 0.26 m); the room's polygon, remembered at the start, pairs
its corners with their own landmarks and brings the pose back. Checks the
last pose of each node against the truth and the MECP counters on
/diagnostics.
"""
import math
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from ekf_slam.msg import FeaturePoint, Features
from geometry_msgs.msg import PoseWithCovarianceStamped, TransformStamped
from tf2_msgs.msg import TFMessage

from ekf_slam_tools.se2 import compose, inverse, transform_point

STEP = 0.1  # s between scans
SLIP = math.radians(5.0)
SEEN_WITHIN = 0.6  # m from the room's centre
CORNERS = [(3.2, 2.6), (-2.9, 3.0), (-3.1, -2.7), (2.8, -3.2)]
RANGE_SIGMA = 0.01  # m
BEARING_SIGMA = 0.01  # rad
NODES = ("nn", "mecp")


def transform_to(pose, point):
    """The map point in the frame of pose."""
    return transform_point(inverse(pose), point)


def drive():
    """(truth, odometry) per scan, and the index of the first scan after the slipping turn."""
    truth, odometry = [], []
    t, o = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)

    def move(true_step, reported_step, n):
        nonlocal t, o
        for _ in range(n):
            t, o = compose(t, true_step), compose(o, reported_step)
            truth.append(t)
            odometry.append(o)

    move((0, 0, 0), (0, 0, 0), 5)
    move((0.1, 0, 0), (0.1, 0, 0), 30)
    move((0, 0, math.pi / 18), (0, 0, (math.pi - SLIP) / 18), 18)
    returning = len(truth)
    move((0.1, 0, 0), (0.1, 0, 0), 30)
    move((0, 0, math.pi / 18), (0, 0, math.pi / 18), 18)
    move((0, 0, 0), (0, 0, 0), 10)
    return truth, odometry, returning


def world(truth, odometry, returning):
    # The map frame is the first pose and nothing is seen in the corridor:
    # on return the estimate is the odometry's, and E maps where a point
    # truly is to where the filter puts it.
    error = compose(odometry[returning], inverse(truth[returning]))
    return CORNERS + [transform_point(error, c) for c in CORNERS]


def features_message(stamp, pose, points):
    message = Features()
    message.header.stamp = stamp
    message.header.frame_id = "laser"
    if math.hypot(pose[0], pose[1]) >= SEEN_WITHIN:
        return message
    for point in points:
        x, y = transform_to(pose, point)
        feature = FeaturePoint()
        feature.x, feature.y = x, y
        feature.range = math.hypot(x, y)
        feature.bearing = math.atan2(y, x)
        feature.range_bearing_covariance = [RANGE_SIGMA ** 2, 0.0, 0.0, BEARING_SIGMA ** 2]
        # The Cartesian covariance of the same reading.
        c, s, r = math.cos(feature.bearing), math.sin(feature.bearing), feature.range
        a = [[c, -r * s], [s, r * c]]
        d = [RANGE_SIGMA ** 2, BEARING_SIGMA ** 2]
        feature.covariance = [sum(a[i][k] * d[k] * a[j][k] for k in range(2))
                              for i in range(2) for j in range(2)]
        feature.kind = "corner"
        feature.context = "corner"
        feature.landmark_candidate = True
        message.points.append(feature)
    return message


def odometry_message(stamp, pose):
    t = TransformStamped()
    t.header.stamp = stamp
    t.header.frame_id = "odom"
    t.child_frame_id = "base_link"
    t.transform.translation.x, t.transform.translation.y = pose[0], pose[1]
    t.transform.rotation.z = math.sin(pose[2] / 2.0)
    t.transform.rotation.w = math.cos(pose[2] / 2.0)
    return TFMessage(transforms=[t])


class MecpLoop(unittest.TestCase):
    def setUp(self):
        rospy.init_node("mecp_loop_test")
        self.lock = threading.Lock()
        self.poses = {name: [] for name in NODES}
        self.mecp = {}
        for name in NODES:
            rospy.Subscriber("/%s/pose" % name, PoseWithCovarianceStamped,
                             lambda m, n=name: self.on_pose(n, m), queue_size=500)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)
        self.tf = rospy.Publisher("/tf", TFMessage, queue_size=100)
        # The laser at base_link, latched on /tf_static.
        self.static = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        mount = TransformStamped()
        mount.header.stamp = rospy.Time.now()
        mount.header.frame_id, mount.child_frame_id = "base_link", "laser"
        mount.transform.rotation.w = 1.0
        self.static.publish(TFMessage(transforms=[mount]))
        self.features = {name: rospy.Publisher("/%s/features" % name, Features, queue_size=100)
                         for name in NODES}

    def on_pose(self, name, message):
        p = message.pose.pose
        yaw = 2.0 * math.atan2(p.orientation.z, p.orientation.w)
        with self.lock:
            self.poses[name].append((message.header.stamp.to_sec(), (p.position.x, p.position.y, yaw)))

    def on_diagnostics(self, message):
        for status in message.status:
            values = {kv.key: kv.value for kv in status.values}
            if "MECP group matches" in values:
                with self.lock:
                    self.mecp = values

    def wait_for(self, condition, timeout):
        deadline = time.time() + timeout
        while time.time() < deadline and not rospy.is_shutdown():
            if condition():
                return True
            time.sleep(0.05)
        return condition()

    def test_mecp_closes_the_loop_nearest_neighbour_misses(self):
        self.assertTrue(self.wait_for(
            lambda: all(p.get_num_connections() > 0 for p in self.features.values())
            and self.tf.get_num_connections() >= 2, 30.0),
            "both ekf_slam_node instances must subscribe to features and /tf")
        time.sleep(1.0)  # the static laser mount reaches both listeners
        truth, odometry, returning = drive()
        points = world(truth, odometry, returning)
        start = rospy.Time.now()
        stamps = []
        for k, (t, o) in enumerate(zip(truth, odometry)):
            stamp = start + rospy.Duration(STEP * (k + 1))
            stamps.append(stamp.to_sec())
            self.tf.publish(odometry_message(stamp, o))
            time.sleep(0.01)  # odometry before the features it places
            message = features_message(stamp, t, points)
            for publisher in self.features.values():
                publisher.publish(message)
            time.sleep(STEP)
        # Poses for the last scan from both nodes, then a fresh diagnostics report.
        last = stamps[-1]
        self.assertTrue(self.wait_for(lambda: all(
            self.poses[n] and abs(self.poses[n][-1][0] - last) < 1e-6 for n in NODES), 20.0),
            "no pose for the last scan: %r" % {n: self.poses[n][-1:] for n in NODES})
        with self.lock:
            self.mecp = {}
        self.assertTrue(self.wait_for(lambda: bool(self.mecp), 10.0), "no MECP counters on /diagnostics")

        def error(name):
            with self.lock:
                estimate = self.poses[name][-1][1]
            return math.hypot(estimate[0] - truth[-1][0], estimate[1] - truth[-1][1])

        def error_before_sight(name):  # 0.7 m from the centre, coming back
            with self.lock:
                by_stamp = dict(self.poses[name])
            estimate = by_stamp[stamps[returning + 22]]
            t = truth[returning + 22]
            return math.hypot(estimate[0] - t[0], estimate[1] - t[1])

        with self.lock:
            counters = dict(self.mecp)
        rospy.loginfo("before sighting the room again: nn %.3f m, mecp %.3f m; at the end: nn %.3f m, "
                      "mecp %.3f m; MECP %r", error_before_sight("nn"), error_before_sight("mecp"),
                      error("nn"), error("mecp"), counters)
        self.assertGreater(error_before_sight("nn"), 0.15)
        self.assertGreater(error_before_sight("mecp"), 0.15)
        self.assertGreater(error("nn"), 0.2, "nearest neighbour closed the loop: the world no longer tests it")
        self.assertLess(error("mecp"), 0.05, "the MECP association did not close the loop")
        self.assertGreater(int(counters["MECP group matches"]), 0)
        self.assertGreaterEqual(int(counters["MECP: pairings changed by the group"]), 4)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "mecp_loop", MecpLoop)
