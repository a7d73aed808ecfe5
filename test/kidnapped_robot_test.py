#!/usr/bin/python3
"""The kidnapped robot in the simulator (test/kidnapped_robot.test).

The simulated P3-DX follows the carton room's waypoint loop on the SLAM
pose while ekf_slam_node maps the room (loop closure on, so the state
holds key scans). Once the robot has driven MAPPED_PATH metres, the test
saves the state (~write_state) and loads it again for localisation
(~load_state, localize_only). While the robot localises, the simulator
carries it to the corner of the loop farther from it, turned half round,
its wheels turning nothing (~teleport): the odometry and so the published
pose go on as if nothing happened. The test checks, against the
simulator's ground truth, that
  - before the carrying the node localises in the loaded map (its scans fit
    it: "fit to the saved map" on /diagnostics above the lost threshold),
  - the node reports lost, and is found again by its global search, within
    FOUND_WITHIN seconds of the carrying (/diagnostics),
  - the pose it then publishes is within PLACED_WITHIN of the truth.
About 40 s.
"""
import math
import os
import tempfile
import threading
import time
import unittest

import rospy
import rostest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from ekf_slam.srv import StateFile, StateFileRequest
from geometry_msgs.msg import Pose2D, PoseWithCovarianceStamped
from nav_msgs.msg import Odometry

from ekf_slam_tools.se2 import compose, interpolate, inverse, yaw_of

WORLD = "carton_layout"
MAPPED_PATH = 6.0  # m driven before the state is saved
# Map frame: two corners of the waypoint loop (config/waypoints/carton_loop.yaml),
# each turned half round from the way the loop passes it; the robot is
# carried to the one farther from where it is.
CORNERS = [(3.8, -0.45, math.pi / 2), (0.5, 0.35, -math.pi / 2)]
FOUND_WITHIN = 10.0  # s after the carrying
PLACED_WITHIN = 0.3  # m from the truth, once found
NODE = "/ekf_slam"


def world_start(world):
    """The world's start pose (the SLAM map frame's origin in the world)."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "config", "worlds",
                        world + ".yaml")
    with open(path) as f:
        x, y, a = yaml.safe_load(f)["start_pose"]
    return (x, y, a)


class KidnappedRobot(unittest.TestCase):
    def setUp(self):
        rospy.init_node("kidnapped_robot_test")
        self.lock = threading.Lock()
        self.start = world_start(WORLD)
        self.truth = []  # [(stamp, x, y, theta)] in the map frame, the last few seconds
        self.driven = 0.0  # m, along the truth
        self.pose = None  # (stamp, pose), the node's
        self.diagnostics = {}
        rospy.Subscriber("/ground_truth/odom", Odometry, self.on_truth, queue_size=10)
        rospy.Subscriber("/pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)
        self.teleport = rospy.Publisher("/simulator/teleport", Pose2D, queue_size=1, latch=True)

    def on_truth(self, message):
        p = message.pose.pose
        world = (p.position.x, p.position.y, yaw_of(p.orientation))
        pose = compose(inverse(self.start), world)
        with self.lock:
            if self.truth:
                self.driven += math.hypot(pose[0] - self.truth[-1][1], pose[1] - self.truth[-1][2])
            self.truth.append((message.header.stamp.to_sec(),) + pose)
            del self.truth[:-500]

    def on_pose(self, message):
        p = message.pose.pose
        with self.lock:
            self.pose = (message.header.stamp.to_sec(),
                         (p.position.x, p.position.y, yaw_of(p.orientation)))

    def on_diagnostics(self, message):
        for status in message.status:
            values = {kv.key: kv.value for kv in status.values}
            if "lost: watched in the loaded state" in values:
                with self.lock:
                    self.diagnostics = values

    def value(self, key, default=None):
        with self.lock:
            return self.diagnostics.get(key, default)

    def wait_for(self, condition, timeout):
        end = time.time() + timeout
        while time.time() < end and not rospy.is_shutdown():
            if condition():
                return True
            time.sleep(0.05)
        return condition()

    def error(self):
        """Position error (m) of the node's last pose against the truth at its stamp."""
        with self.lock:
            if self.pose is None:
                return float("inf")
            stamp, p = self.pose
            t = interpolate(list(self.truth), stamp)
        return float("inf") if t is None else math.hypot(p[0] - t[0], p[1] - t[1])

    def measured_error(self):
        """error(), once the truth covers the last pose's stamp (it comes at 50 Hz)."""
        self.wait_for(lambda: math.isfinite(self.error()), 2.0)
        return self.error()

    def test_lost_and_found_again(self):
        self.assertTrue(self.wait_for(lambda: self.driven > MAPPED_PATH, 120.0),
                        "the robot did not drive %.1f m" % MAPPED_PATH)
        folder = tempfile.mkdtemp(prefix="kidnapped_robot_")
        path = os.path.join(folder, "room.state")
        rospy.wait_for_service(NODE + "/write_state", 10.0)
        written = rospy.ServiceProxy(NODE + "/write_state", StateFile)(StateFileRequest(path=path))
        self.assertTrue(written.success, written.message)
        loaded = rospy.ServiceProxy(NODE + "/load_state", StateFile)(
            StateFileRequest(path=path, localize_only=True))
        self.assertTrue(loaded.success, loaded.message)
        print("write_state: %s\nload_state: %s" % (written.message, loaded.message))

        # Localising in the loaded map: its scans fit it.
        self.assertTrue(self.wait_for(lambda: self.value("lost: watched in the loaded state") == "True"
                                      and float(self.value("fit to the saved map", "0")) > 0.3,
                                      10.0),
                        "not localising in the loaded state: %s" % self.diagnostics)
        self.assertEqual(self.value("lost"), "False")
        fit_before = float(self.value("fit to the saved map"))
        error_before = self.measured_error()

        lost_before = int(self.value("times lost"))
        found_before = int(self.value("times found again (global search)"))
        with self.lock:
            here = self.truth[-1][1:3]
        to = max(CORNERS, key=lambda c: math.hypot(c[0] - here[0], c[1] - here[1]))
        carried_at = time.time()
        self.teleport.publish(Pose2D(x=to[0], y=to[1], theta=to[2]))
        self.assertTrue(self.wait_for(lambda: int(self.value("times lost")) > lost_before,
                                      FOUND_WITHIN),
                        "never reported lost: %s" % self.diagnostics)
        lost_after = time.time() - carried_at
        found = self.wait_for(
            lambda: int(self.value("times found again (global search)")) > found_before,
            FOUND_WITHIN - lost_after)
        found_after = time.time() - carried_at
        self.assertTrue(found, "not found again within %.0f s of the carrying: %s"
                        % (FOUND_WITHIN, self.diagnostics))
        # The next poses are published from the place found.
        time.sleep(1.0)
        error_after = self.measured_error()
        print("before the carrying: fit %.3f, error %.3f m; carried %.1f m to (%.1f, %.1f); lost "
              "%.1f s after it, found %.1f s after it (%s global searches); then %.3f m from "
              "the truth" % (fit_before, error_before, math.hypot(to[0] - here[0], to[1] - here[1]),
                             to[0], to[1], lost_after, found_after,
                             self.value("global searches"), error_after))
        self.assertLess(error_after, PLACED_WITHIN)
        self.assertEqual(self.value("lost"), "False")


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "kidnapped_robot", KidnappedRobot)
