#!/usr/bin/python3
"""A laser mounted upside down (test/inverted_laser.test).

Writes a copy of the first --seconds of the bag that also holds the scans
as an upside-down laser records them (/scan_inverted: each scan's beams in
reverse order, frame laser_inverted, base_link -> laser_inverted rolled by
pi) and as a laser pitched by 10 deg would be announced (/scan_pitched,
frame laser_pitched), and plays it into three ekf_slam_nodes, one per
scan topic. Checks:
- the upright and the inverted node publish the same poses and the same
  landmarks, within 1 cm (an unmirrored inverted scan maps a mirror image:
  metres off);
- /diagnostics names each mount; the pitched node WARNs with its tilt.
"""
import argparse
import copy
import math
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped, TransformStamped
from ekf_slam.msg import LandmarkMap

from ekf_slam_tools.se2 import wrap, yaw_of

TOLERANCE = 0.01  # m (and rad for the headings): the same map
PITCH = math.radians(10.0)
NODES = ("upright", "inverted", "pitched")


def mount(parent, child, stamp, roll=0.0, pitch=0.0):
    t = TransformStamped()
    t.header.frame_id = parent
    t.header.stamp = stamp
    t.child_frame_id = child
    # roll about x, then pitch about y: q = q_y(pitch) q_x(roll)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    t.transform.rotation.w = cp * cr
    t.transform.rotation.x = cp * sr
    t.transform.rotation.y = sp * cr
    t.transform.rotation.z = -sp * sr
    return t


class InvertedLaser(unittest.TestCase):
    args = None

    def setUp(self):
        if not os.path.exists(self.args.bag):
            self.skipTest(self.args.bag + " not found (the datasets live in ../shared/datasets)")
        self.lock = threading.Lock()
        self.poses = {n: {} for n in NODES}
        self.maps = {}
        self.status = {}  # node -> (level, message, {key: value})
        for n in NODES:
            rospy.Subscriber("/%s/pose" % n, PoseWithCovarianceStamped, self.on_pose, n,
                             queue_size=10000)
            rospy.Subscriber("/%s/landmark_map" % n, LandmarkMap, self.on_map, n, queue_size=10)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=100)

    def on_pose(self, msg, node):
        p = msg.pose.pose
        with self.lock:
            self.poses[node][round(msg.header.stamp.to_sec(), 6)] = (
                p.position.x, p.position.y, yaw_of(p.orientation))

    def on_map(self, msg, node):
        with self.lock:
            self.maps[node] = msg

    def on_diagnostics(self, msg):
        with self.lock:
            for s in msg.status:
                for n in NODES:
                    if s.name.startswith("%s/" % n):  # "upright/upright: EKF-SLAM"
                        self.status[n] = (s.level, s.message, {kv.key: kv.value for kv in s.values})

    def write_bag(self, path):
        with rosbag.Bag(self.args.bag) as source, rosbag.Bag(path, "w") as out:
            end = source.get_start_time() + self.args.seconds
            for topic, msg, t in source.read_messages():
                if t.to_sec() > end:
                    break
                if topic == "/tf_static":
                    msg = copy.deepcopy(msg)
                    stamp = msg.transforms[0].header.stamp
                    msg.transforms.append(mount("base_link", "laser_inverted", stamp, roll=math.pi))
                    msg.transforms.append(mount("base_link", "laser_pitched", stamp, pitch=PITCH))
                out.write(topic, msg, t)
                if topic == "/scan":
                    inverted = copy.deepcopy(msg)
                    inverted.header.frame_id = "laser_inverted"
                    inverted.ranges = list(reversed(msg.ranges))
                    inverted.intensities = list(reversed(msg.intensities))
                    inverted.angle_min, inverted.angle_max = -msg.angle_max, -msg.angle_min
                    out.write("/scan_inverted", inverted, t)
                    pitched = copy.deepcopy(msg)
                    pitched.header.frame_id = "laser_pitched"
                    out.write("/scan_pitched", pitched, t)

    def test_an_inverted_laser_maps_as_the_upright_one(self):
        work = tempfile.mkdtemp(prefix="ekf_slam_inverted_")
        try:
            bag = os.path.join(work, "mounts.bag")
            self.write_bag(bag)
            for n in NODES:
                rospy.wait_for_service("/%s/%s/reset" % (n, n), timeout=60.0)
            time.sleep(1.0)
            subprocess.check_call(["rosbag", "play", "--clock", "--quiet", "-r",
                                   str(self.args.rate), bag])
        finally:
            shutil.rmtree(work, ignore_errors=True)
        last = -1
        while sum(len(p) for p in self.poses.values()) != last:
            last = sum(len(p) for p in self.poses.values())
            time.sleep(2.0)
        time.sleep(2.0)  # one more /diagnostics

        upright, inverted = self.poses["upright"], self.poses["inverted"]
        common = sorted(set(upright) & set(inverted))
        print("poses: upright %d, inverted %d, common %d" % (len(upright), len(inverted),
                                                               len(common)))
        self.assertGreater(len(common), 500)
        self.assertGreater(len(common), 0.95 * max(len(upright), len(inverted)))
        worst = max(math.hypot(upright[t][0] - inverted[t][0], upright[t][1] - inverted[t][1])
                    for t in common)
        worst_heading = max(abs(wrap(upright[t][2] - inverted[t][2])) for t in common)
        travelled = sum(math.hypot(upright[b][0] - upright[a][0], upright[b][1] - upright[a][1])
                        for a, b in zip(common, common[1:]))
        print("upright vs inverted: largest pose difference %.6f m, %.6f rad over %.1f m driven"
              % (worst, worst_heading, travelled))
        self.assertGreater(travelled, 20.0, "the robot hardly moved: nothing shown")
        self.assertLess(worst, TOLERANCE)
        self.assertLess(worst_heading, TOLERANCE)

        a, b = self.maps["upright"], self.maps["inverted"]
        self.assertGreater(len(a.landmarks), 10)
        self.assertEqual(len(a.landmarks), len(b.landmarks))
        theirs = {l.id: l for l in b.landmarks}
        for l in a.landmarks:
            self.assertIn(l.id, theirs)
            self.assertLess(math.hypot(l.x - theirs[l.id].x, l.y - theirs[l.id].y), TOLERANCE)

        self.assertEqual(self.status["upright"][2].get("laser mount"), "upright")
        self.assertEqual(self.status["inverted"][2].get("laser mount"),
                         "upside down (scans mirrored)")
        level, message, values = self.status["pitched"]
        print("pitched: %s" % message)
        self.assertEqual(level, DiagnosticStatus.WARN)
        self.assertIn("laser_pitched is tilted 10.0 deg", message)
        self.assertAlmostEqual(float(values["laser tilt [deg]"]), 10.0, places=1)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--bag", required=True)
    parser.add_argument("--seconds", type=float, default=150.0)
    parser.add_argument("--rate", type=float, default=4.0)
    args, _ = parser.parse_known_args(rospy.myargv(sys.argv)[1:])
    InvertedLaser.args = args
    rospy.init_node("inverted_laser_test")
    rostest.rosrun("ekf_slam", "inverted_laser", InvertedLaser)
