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
- /diagnostics names each mount; the pitched node WARNs with its tilt;
- the pitched node (publish_tf: false) sends no map -> odom, the others do.
"""
import copy
import math
import os
import shutil
import tempfile
import threading
import time

import rosbag
import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped, TransformStamped
from ekf_slam.msg import LandmarkMap
from tf2_msgs.msg import TFMessage

from ekf_slam_tools.replay_test import ReplayTest, main
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


class InvertedLaser(ReplayTest):
    def setUp(self):
        super().setUp()
        self.lock = threading.Lock()
        self.poses = {n: {} for n in NODES}
        self.maps = {}
        self.map_frames = set()  # parents of the map -> odom transforms on /tf
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=10000)
        for n in NODES:
            rospy.Subscriber("/%s/pose" % n, PoseWithCovarianceStamped, self.on_pose, n,
                             queue_size=10000)
            rospy.Subscriber("/%s/landmark_map" % n, LandmarkMap, self.on_map, n, queue_size=10)

    def on_pose(self, msg, node):
        p = msg.pose.pose
        with self.lock:
            self.poses[node][round(msg.header.stamp.to_sec(), 6)] = (
                p.position.x, p.position.y, yaw_of(p.orientation))

    def on_tf(self, msg):
        with self.lock:
            self.map_frames.update(t.header.frame_id for t in msg.transforms
                                   if t.child_frame_id == "odom")

    def on_map(self, msg, node):
        with self.lock:
            self.maps[node] = msg

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
                self.wait_for_node("/%s/%s/reset" % (n, n))
            self.play(bag, seconds=0)  # the whole copy
        finally:
            shutil.rmtree(work, ignore_errors=True)
        self.settle(lambda: sum(len(p) for p in self.poses.values()))
        time.sleep(2.0)  # one more /diagnostics

        upright, inverted = self.poses["upright"], self.poses["inverted"]
        common = sorted(set(upright) & set(inverted))
        print("poses: upright %d, inverted %d, common %d" % (len(upright), len(inverted),
                                                               len(common)))
        for n in NODES:
            print("%s: scans received %s, processed %s; dropped %s" % (
                n, self.diagnostics.values(n + "/").get("scans received"),
                self.diagnostics.values(n + "/").get("scans processed"),
                self.diagnostics.drops(n + "/") or "none"))
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

        self.assertEqual(self.diagnostics.values("upright/").get("laser mount"), "upright")
        self.assertEqual(self.diagnostics.values("inverted/").get("laser mount"),
                         "upside down (scans mirrored)")
        level, message, values = self.diagnostics.status("pitched/")
        print("pitched: %s" % message)
        self.assertEqual(level, DiagnosticStatus.WARN)
        self.assertIn("laser_pitched is tilted 10.0 deg", message)
        self.assertAlmostEqual(float(values["laser tilt [deg]"]), 10.0, places=1)

        print("map -> odom sent by: %s" % sorted(self.map_frames))
        self.assertGreater(len(self.poses["pitched"]), 500)
        self.assertEqual(self.map_frames, {"map_upright", "map_inverted"})


if __name__ == "__main__":
    main(InvertedLaser, "inverted_laser", seconds=150.0, rate=4.0)
