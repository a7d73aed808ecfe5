#!/usr/bin/python3
"""A real log with loops through the live node (test/live_loop_replay.test).

1. Plays the first --seconds of the bag on /clock at --rate into slam.launch
   (built-in configuration) and records what the node publishes: pose,
   map, loop_closed_path, tf map -> odom, /diagnostics.
2. Runs ekf_slam_offline on the same scans (--max-scans: as many as the
   node processed), with the same loop_closure.correction_delay, and
   compares its trajectory_live.txt with the published poses, scan by scan.

Checks: the map arrives while the log plays, with values -1 / 0 / 100 only
and walls in it; loops are accepted and each moves map -> odom far more
than an ordinary scan does; and the published poses are the offline causal
poses. With a correction delay d >= 0 (the deterministic mode) every scan
agrees: the node's back end, on its own thread, hands each scan the graph
as it stood d scans earlier, as the offline runner does. With d = -1 (a
correction takes effect as soon as the back end has it) they agree except
in short runs of scans after a correction that the node's back end
delivered later than the offline runner's.
"""
import argparse
import bisect
import math
import os
import subprocess
import sys
import tempfile
import time
import unittest

import rosbag
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Path
from tf2_msgs.msg import TFMessage

from ekf_slam_tools.se2 import wrap, yaw_of

POSITION_TOLERANCE = 0.01  # m: live and offline agree to this …
HEADING_TOLERANCE = math.radians(0.1)  # … and this at every compared scan
LATE_CORRECTION_SCANS = 50  # d = -1: the longest run of scans a correction may arrive late


class LiveLoopReplay(unittest.TestCase):
    args = None

    def setUp(self):
        if not os.path.exists(self.args.bag):
            self.skipTest(self.args.bag + " not found (the datasets live in ../shared/datasets)")
        self.poses = []  # (stamp, x, y, theta)
        self.map_to_odom = []  # (stamp, x, y, theta)
        self.odom_to_base = []  # (stamp, x, y)
        self.maps = []
        self.loop_paths = []  # stamps of loop_closed_path messages
        self.loops_accepted = 0
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10000)
        rospy.Subscriber("map", OccupancyGrid, self.on_map, queue_size=5)
        rospy.Subscriber("loop_closed_path", Path, self.on_loop_path, queue_size=100)
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=10000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=100)

    def on_pose(self, msg):
        p = msg.pose.pose
        self.poses.append((msg.header.stamp.to_sec(), p.position.x, p.position.y,
                           yaw_of(p.orientation)))

    def on_map(self, msg):
        self.maps.append(msg)

    def on_loop_path(self, msg):
        self.loop_paths.append(msg.header.stamp.to_sec())

    def on_tf(self, msg):
        for t in msg.transforms:
            r = t.transform
            if t.header.frame_id == "map" and t.child_frame_id == "odom":
                self.map_to_odom.append((t.header.stamp.to_sec(), r.translation.x,
                                         r.translation.y, yaw_of(r.rotation)))
            elif t.header.frame_id == "odom" and t.child_frame_id == "base_link":
                self.odom_to_base.append((t.header.stamp.to_sec(), r.translation.x,
                                          r.translation.y))

    def on_diagnostics(self, msg):
        for status in msg.status:
            for kv in status.values:
                if kv.key == "loops accepted":
                    self.loops_accepted = max(self.loops_accepted, int(kv.value))

    def play(self):
        deadline = time.time() + 30.0
        while rospy.get_param("/use_sim_time", False) is not True and time.time() < deadline:
            time.sleep(0.1)
        time.sleep(2.0)  # the node and its subscriptions are up
        subprocess.check_call(["rosbag", "play", "--clock", "--quiet", "-r", str(self.args.rate),
                               "-u", str(self.args.seconds), self.args.bag])
        # The node finishes its queue, the map thread its last grid.
        last = -1
        while len(self.poses) != last:
            last = len(self.poses)
            time.sleep(2.0)

    def offline(self, scans):
        out = tempfile.mkdtemp(prefix="ekf_slam_live_loop_")
        exe = subprocess.check_output(["catkin_find", "--first-only", "--libexec", "ekf_slam",
                                       "ekf_slam_offline"]).decode().split()[0]
        # The odometry looked up in tf as the node looks it up (the built-in
        # defaults otherwise).
        config = os.path.join(out, "odometry_from_tf.yaml")
        with open(config, "w") as f:
            f.write("input:\n  odometry_source: tf\n")
            f.write("loop_closure:\n  correction_delay: %d\n" % self.args.correction_delay)
        subprocess.check_call([exe, "--bag", self.args.bag, "--out", out, "--no-maps",
                               "--config", config, "--max-scans", str(scans)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        rows = []
        with open(os.path.join(out, "trajectory_live.txt")) as f:
            for line in f:
                if line.strip() and not line.startswith("#"):
                    rows.append(tuple(float(v) for v in line.split()[:4]))
        return rows

    def test_live_map_loops_and_causal_poses(self):
        self.play()
        self.assertGreater(len(self.poses), 1000, "the node published too few poses")

        # The map, while the log played: trinary values, walls and free space.
        self.assertGreater(len(self.maps), 2, "no map published while the log played")
        grid = self.maps[-1]
        values = set(grid.data)
        self.assertTrue(values <= {-1, 0, 100}, "map values %s" % sorted(values))
        self.assertGreater(sum(1 for v in grid.data if v == 100), 1000)
        self.assertGreater(sum(1 for v in grid.data if v == 0), 10000)
        self.assertEqual(grid.header.frame_id, "map")

        # Loops close, and each moves map -> odom far more than a scan does.
        self.assertGreater(self.loops_accepted, 0)
        self.assertGreater(len(self.loop_paths), 0)
        # How far each change of map -> odom moved the robot in the map: at
        # the robot's odometry position p at a scan's stamp t, the largest
        # |T' p - T p| over the transforms T' stamped in [t, t + 3 s], T the
        # last one stamped before t. (Measured at the robot, a heading
        # correction far from the odom origin does not count as a jump; and
        # stamp-sorted, a node lagging behind its odometry, whose timer
        # re-sends the old transform stamped with the newest odometry,
        # still shows the jump within the window.) At each loop
        # optimisation against the same at ordinary scans far from any loop.
        tf_sorted = sorted(self.map_to_odom)
        stamps_tf = [e[0] for e in tf_sorted]
        odom_sorted = sorted(self.odom_to_base)
        stamps_odom = [e[0] for e in odom_sorted]

        def apply(transform, x, y):
            _, tx, ty, th = transform
            return (tx + math.cos(th) * x - math.sin(th) * y,
                    ty + math.sin(th) * x + math.cos(th) * y)

        def move_across(t):
            k = bisect.bisect_left(stamps_tf, t) - 1
            j = bisect.bisect_right(stamps_odom, t) - 1
            if k < 0 or j < 0:
                return 0.0
            _, px, py = odom_sorted[j]
            ax, ay = apply(tf_sorted[k], px, py)
            end = bisect.bisect_right(stamps_tf, t + 3.0)
            return max([math.hypot(bx - ax, by - ay) for bx, by in
                        (apply(e, px, py) for e in tf_sorted[k + 1:end])] or [0.0])

        at_loops = [move_across(t) for t in self.loop_paths]
        quiet = [p[0] for p in self.poses if all(abs(p[0] - t) > 5.0 for t in self.loop_paths)]
        ordinary = sorted(move_across(t) for t in quiet[::10])[len(quiet[::10]) // 2]
        print("map -> odom steps at the robot: median %.5f m, at the %d loop optimisations up to "
              "%.3f m" % (ordinary, len(at_loops), max(at_loops) if at_loops else 0.0))
        self.assertTrue(at_loops, "no map -> odom published at a loop optimisation")
        self.assertGreater(max(at_loops), max(0.01, 10 * ordinary))

        # The published poses are the offline runner's causal poses.
        with rosbag.Bag(self.args.bag) as bag:
            stamps = [m.header.stamp.to_sec() for _, m, _ in bag.read_messages(topics=["/scan"])]
        last = self.poses[-1][0]
        scans = sum(1 for s in stamps if s <= last + 1e-6)
        offline = self.offline(scans)
        live = {round(p[0], 6): p for p in self.poses}
        compared = worst_position = worst_heading = 0.0
        outside = 0
        first_outside = None
        runs = []  # lengths of the runs of consecutive scans outside the tolerance
        for stamp, x, y, theta in offline:
            p = live.get(round(stamp, 6))
            if p is None:
                continue
            compared += 1
            d = math.hypot(p[1] - x, p[2] - y)
            h = abs(wrap(p[3] - theta))
            worst_position = max(worst_position, d)
            worst_heading = max(worst_heading, h)
            if d > POSITION_TOLERANCE or h > HEADING_TOLERANCE:
                outside += 1
                runs.append(runs.pop() + 1 if runs and runs[-1] > 0 else 1)
                if first_outside is None:
                    first_outside = (int(compared) - 1, stamp, d, math.degrees(h))
            elif runs and runs[-1] > 0:
                runs.append(0)
        runs = [r for r in runs if r > 0]
        print("live vs offline causal poses: %d of %d scans compared, %d outside 1 cm / 0.1 deg,"
              " largest %.6f m, %.6f deg" % (compared, len(offline), outside, worst_position,
                                              math.degrees(worst_heading)))
        print("first scan outside: %s; runs of scans outside: %s" % (first_outside, runs))
        self.assertGreater(compared, 0.98 * len(offline), "the node dropped scans")
        if self.args.correction_delay >= 0:
            self.assertEqual(outside, 0)
            self.assertLess(worst_position, 1e-6)
        else:
            self.assertLessEqual(len(runs), len(self.loop_paths),
                                 "more disagreements than back-end optimisations")
            self.assertLessEqual(max(runs or [0]), LATE_CORRECTION_SCANS)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--bag", required=True)
    parser.add_argument("--seconds", type=float, default=1000.0)
    parser.add_argument("--rate", type=float, default=10.0)
    parser.add_argument("--correction-delay", type=int, default=-1)
    args, _ = parser.parse_known_args(rospy.myargv(sys.argv)[1:])
    LiveLoopReplay.args = args
    rospy.init_node("live_loop_replay_test")
    rostest.rosrun("ekf_slam", "live_loop_replay", LiveLoopReplay)
