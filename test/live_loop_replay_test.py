#!/usr/bin/python3
"""A real log with loops through the live node (test/live_loop_replay.test).

1. Plays the first --seconds of the bag on /clock at --rate into slam.launch
   (built-in configuration) and records what the node publishes: pose,
   map, loop_closed_path, tf map -> odom, /diagnostics.
2. Runs ekf_slam_offline on the scans the node processed (a copy of the
   log without the scans it published no pose for: those it dropped, e.g.
   when a loaded machine let it fall behind the transforms it buffers),
   with the same loop_closure.correction_delay, and compares its
   trajectory_live.txt with the published poses, scan by scan.

Checks: the map arrives while the log plays, with values -1 / 0 / 100 only
and walls in it; loops are accepted and each moves map -> odom far more
than an ordinary scan does; and the published poses are the offline causal
poses. (Each loop's step in map -> odom is measured from the published
poses and the odometry, stamped with their scans, so that it does not
depend on how late a transform reached this process.) With a correction
delay d >= 0 (the deterministic mode) every scan
agrees: the node's back end, on its own thread, hands each scan the graph
as it stood d scans earlier, as the offline runner does. With d = -1 (a
correction takes effect as soon as the back end has it) they agree except
in short runs of scans after a correction that the node's back end
delivered later than the offline runner's.
"""
import bisect
import math
import os
import re
import shutil
import struct
import subprocess
import tempfile
import time

import rosbag
import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Path
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker, MarkerArray

from ekf_slam_tools.replay_test import ReplayTest, main
from ekf_slam_tools.se2 import wrap, yaw_of

POSITION_TOLERANCE = 0.01  # m: live and offline agree to this …
HEADING_TOLERANCE = math.radians(0.1)  # … and this at every compared scan
# d = -1: how late (wall clock) a correction may reach the published poses
# after the offline runner applies it: the back end's loop search and
# optimisation for one key scan, on a shared 2-core machine (1.0 s idle;
# 1.1 s beside two busy loops; 1.53 s in a clean-clone `make test`, beside
# the simulated robot's lane and an exploration). In scans it is this times
# the replay rate times the log's scan rate (ACES at 20x: about 200 scans);
# a correction that never arrived would keep the poses apart until the
# next optimisation, some 240 scans later on average.
LATE_CORRECTION_SECONDS = 2.0


def scan_stamp(raw):
    """The header stamp of a LaserScan read raw from a bag, in seconds, as
    rospy converts it (the header comes first: seq, stamp.secs, stamp.nsecs)."""
    return rospy.Time(*struct.unpack_from("<II", raw[1], 4)).to_sec()


class LiveLoopReplay(ReplayTest):
    def setUp(self):
        super().setUp()
        self.poses = []  # (stamp, x, y, theta)
        self.map_to_odom = []  # (stamp, x, y, theta, wall time received)
        self.pose_wall = {}  # scan stamp (rounded to 1 µs) -> wall time its pose arrived
        self.odom_to_base = []  # (stamp, x, y, theta)
        self.maps = []
        self.loop_paths = []  # stamps of loop_closed_path messages
        self.last_loop_path = None
        self.pose_graph = None  # the newest pose_graph markers, by namespace
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10000)
        rospy.Subscriber("map", OccupancyGrid, self.on_map, queue_size=5)
        rospy.Subscriber("loop_closed_path", Path, self.on_loop_path, queue_size=100)
        rospy.Subscriber("pose_graph", MarkerArray, self.on_pose_graph, queue_size=5)
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=10000)

    def on_pose(self, msg):
        p = msg.pose.pose
        self.pose_wall[round(msg.header.stamp.to_sec(), 6)] = time.time()
        self.poses.append((msg.header.stamp.to_sec(), p.position.x, p.position.y,
                           yaw_of(p.orientation)))

    def on_map(self, msg):
        self.maps.append(msg)

    def on_loop_path(self, msg):
        self.loop_paths.append(round(msg.header.stamp.to_sec(), 6))
        self.last_loop_path = msg

    def on_pose_graph(self, msg):
        self.pose_graph = {m.ns: m for m in msg.markers}

    def on_tf(self, msg):
        for t in msg.transforms:
            r = t.transform
            if t.header.frame_id == "map" and t.child_frame_id == "odom":
                self.map_to_odom.append((t.header.stamp.to_sec(), r.translation.x,
                                         r.translation.y, yaw_of(r.rotation), time.time()))
            elif t.header.frame_id == "odom" and t.child_frame_id == "base_link":
                self.odom_to_base.append((t.header.stamp.to_sec(), r.translation.x,
                                          r.translation.y, yaw_of(r.rotation)))

    def play_and_settle(self):
        self.wait_for_node()
        self.play()
        self.settle(lambda: len(self.poses))  # the node's queue, the map thread's last grid

    def offline(self, processed):
        """trajectory_live.txt of ekf_slam_offline on the scans in `processed`,
        and the back end's optimisations in that run (its report).

        A scan the node dropped never touched its state: the offline runner
        must not see it either. It reads a copy of the log with every other
        message (odometry, transforms) and only the scans whose stamps
        (rounded to 1 µs) are in `processed`.
        """
        out = tempfile.mkdtemp(prefix="ekf_slam_live_loop_")
        try:
            bag = os.path.join(out, "processed_scans.bag")
            kept = 0
            with rosbag.Bag(self.args.bag) as source, rosbag.Bag(bag, "w") as copy:
                for topic, raw, t in source.read_messages(raw=True):
                    if topic == "/scan":
                        if round(scan_stamp(raw), 6) not in processed:
                            continue
                        kept += 1
                    copy.write(topic, raw, t, raw=True)
            exe = subprocess.check_output(["catkin_find", "--first-only", "--libexec", "ekf_slam",
                                           "ekf_slam_offline"]).decode().split()[0]
            # The odometry looked up in tf as the node looks it up (the
            # built-in defaults otherwise).
            config = os.path.join(out, "odometry_from_tf.yaml")
            with open(config, "w") as f:
                f.write("input:\n  odometry_source: tf\n")
                f.write("loop_closure:\n  correction_delay: %d\n" % self.args.correction_delay)
            subprocess.check_call([exe, "--bag", bag, "--out", out, "--no-maps", "--config",
                                   config, "--max-scans", str(kept)],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            rows = []
            with open(os.path.join(out, "trajectory_live.txt")) as f:
                for line in f:
                    if line.strip() and not line.startswith("#"):
                        rows.append(tuple(float(v) for v in line.split()[:4]))
            with open(os.path.join(out, "report.txt")) as f:
                optimisations = re.search(r"(\d+) optimisations", f.read())
            self.assertIsNotNone(optimisations, "no optimisation count in the offline report")
            return rows, int(optimisations.group(1))
        finally:
            shutil.rmtree(out, ignore_errors=True)

    def corrections(self):
        """How far each scan's map -> odom moved the robot in the map.

        The node publishes map -> odom = pose ∘ odometry⁻¹ at every scan, so
        the change at scan i, measured at the robot, is the distance between
        the published pose and the previous pose carried forward by the
        odometry increment (odom -> base_link from /tf, interpolated at the
        scan stamps). Taken from the poses, stamped with their scans, it does
        not depend on when the transforms reached this process.

        Returns {stamp: step} and after(stamp): for the scan at stamp, the
        distances at the robot between its map -> odom and each map -> odom
        on /tf that could carry it: stamped no earlier than the scan, and
        received within seconds (wall clock) of the scan's pose. (The stamp
        alone does not bound it: when the node runs behind the log, its
        timer has already re-sent the previous estimate stamped with newer
        odometry, and the scan's estimate goes out just after that.)
        """
        odom = sorted(self.odom_to_base)
        odom_stamps = [o[0] for o in odom]

        def odometry_at(t):
            k = bisect.bisect_left(odom_stamps, t)
            if k == 0 or k == len(odom):
                return None
            (t0, x0, y0, h0), (t1, x1, y1, h1) = odom[k - 1], odom[k]
            f = 0.0 if t1 <= t0 else (t - t0) / (t1 - t0)
            return (x0 + f * (x1 - x0), y0 + f * (y1 - y0), h0 + f * wrap(h1 - h0))

        def compose(a, b):
            c, s = math.cos(a[2]), math.sin(a[2])
            return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])

        def inverse(a):
            c, s = math.cos(a[2]), math.sin(a[2])
            return (-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2])

        poses = sorted({round(p[0], 6): p for p in self.poses}.values())
        steps, map_to_odom = {}, {}
        previous = None
        for stamp, x, y, theta in poses:
            o = odometry_at(stamp)
            if o is None:
                previous = None
                continue
            map_to_odom[round(stamp, 6)] = (compose((x, y, theta), inverse(o)), o)
            if previous is not None:
                (px, py, ptheta), po = previous
                predicted = compose((px, py, ptheta), compose(inverse(po), o))
                steps[round(stamp, 6)] = math.hypot(x - predicted[0], y - predicted[1])
            previous = ((x, y, theta), o)

        tf_sorted = sorted(self.map_to_odom)
        tf_stamps = [e[0] for e in tf_sorted]

        def after(stamp):
            transform, o = map_to_odom[round(stamp, 6)]
            ours = compose(transform, o)
            received = self.pose_wall[round(stamp, 6)]
            first = bisect.bisect_left(tf_stamps, stamp)
            for _, tx, ty, th, wall in tf_sorted[first:]:
                if received - 2.0 <= wall <= received + 5.0:
                    theirs = compose((tx, ty, th), o)
                    yield math.hypot(theirs[0] - ours[0], theirs[1] - ours[1])

        return steps, after

    def test_live_map_loops_and_causal_poses(self):
        self.play_and_settle()
        self.assertGreater(len(self.poses), 1000, "the node published too few poses")

        # /diagnostics runs on wall time: it keeps coming (every
        # ~diagnostic_period, 1 s) after the log, and with it the simulated
        # clock, has stopped and the node has caught up.
        settled = time.time()
        time.sleep(3.5)
        walls = self.diagnostics.walls()
        late = [t for t in walls if t > settled]
        self.assertGreaterEqual(len(late), 2, "%d /diagnostics in the 3.5 s after the clock "
                                "stopped (%d before)" % (len(late), len(walls)))

        # The map, while the log played: trinary values, walls and free space.
        self.assertGreater(len(self.maps), 2, "no map published while the log played")
        grid = self.maps[-1]
        values = set(grid.data)
        self.assertTrue(values <= {-1, 0, 100}, "map values %s" % sorted(values))
        self.assertGreater(sum(1 for v in grid.data if v == 100), 1000)
        self.assertGreater(sum(1 for v in grid.data if v == 0), 10000)
        self.assertEqual(grid.header.frame_id, "map")

        # Loops close, and each moves map -> odom far more than a scan does.
        self.assertGreater(self.diagnostics.count("loops accepted"), 0)
        self.assertGreater(len(self.loop_paths), 0)
        steps, after = self.corrections()
        at_loops = [steps[t] for t in self.loop_paths if t in steps]
        quiet = [s for t, s in steps.items() if all(abs(t - u) > 5.0 for u in self.loop_paths)]
        ordinary = sorted(quiet)[len(quiet) // 2]
        print("map -> odom steps at the robot: median %.5f m, at the %d loop optimisations up to "
              "%.3f m" % (ordinary, len(at_loops), max(at_loops) if at_loops else 0.0))
        self.assertTrue(at_loops, "no pose published at a loop optimisation")
        largest = max(at_loops)
        self.assertGreater(largest, max(0.01, 10 * ordinary))
        # ... and that very transform went out on /tf (to 0.1 mm: the next
        # scan's moves it by about the median step, 1 cm), published with the
        # loop's scan stamp or, when the node ran behind, just after the
        # newer stamps its timer had used.
        loop = max((t for t in self.loop_paths if t in steps), key=lambda t: steps[t])
        candidates = list(after(loop))
        self.assertTrue(any(d < 1e-4 for d in candidates),
                        "the corrected map -> odom of the loop at %.3f was never on /tf: of %d "
                        "transforms sent around it the closest is %s m away" %
                        (loop, len(candidates), min(candidates) if candidates else None))

        # The pose graph as rviz draws it: a node per key scan of the last
        # loop-closed path, and the loops between two of them.
        self.assertIsNotNone(self.pose_graph, "no pose_graph markers")
        nodes = self.pose_graph["pose_graph_nodes"].points
        keys = {(round(p.pose.position.x, 6), round(p.pose.position.y, 6))
                for p in self.last_loop_path.poses}
        self.assertEqual(len(nodes), len(self.last_loop_path.poses))
        self.assertEqual({(round(p.x, 6), round(p.y, 6)) for p in nodes}, keys)
        loops = self.pose_graph["pose_graph_loops"]
        self.assertEqual(loops.action, Marker.ADD, "no loop drawn")
        self.assertEqual(len(loops.points) % 2, 0)
        self.assertTrue(all((round(p.x, 6), round(p.y, 6)) in keys for p in loops.points),
                        "a loop drawn from or to a point that is no key scan")
        print("pose graph: %d key scans, %d loops drawn" % (len(nodes), len(loops.points) // 2))

        # The published poses are the offline runner's causal poses.
        with rosbag.Bag(self.args.bag) as bag:
            stamps = [scan_stamp(raw) for _, raw, _ in bag.read_messages(topics=["/scan"], raw=True)]
        last = self.poses[-1][0]
        scans = sum(1 for s in stamps if s <= last + 1e-6)
        scan_rate = (scans - 1) / max(1e-9, last - stamps[0])  # scans per second of log
        live = {round(p[0], 6): p for p in self.poses}
        received = self.diagnostics.count("scans received")
        drops = self.diagnostics.drops()
        # Scans the node dropped (a loaded machine lets it fall behind the
        # transforms it buffers) are left out of the comparison, not
        # compared with an offline run that used them; most must be there.
        print("the node received %d and published poses for %d of the log's %d scans up to %.3f;"
              " dropped: %s" % (received, len(live), scans, last, drops or "none"))
        self.assertGreater(len(live), 0.9 * scans, "the node dropped scans: %s, received %d" %
                           (drops, received))
        offline, optimisations = self.offline(live)
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
        # Every scan the offline runner processed was one the node published.
        self.assertGreater(compared, 0.999 * len(offline), "scans missing from the live poses")
        if self.args.correction_delay >= 0:
            self.assertEqual(outside, 0, "first scan outside: %s" % (first_outside,))
            self.assertLess(worst_position, 1e-6)
        else:
            # Each correction the back end makes (an optimisation) lands at
            # its own scan offline and when ready live: at most one run of
            # disagreement each. (The node's loop_closed_path, one message
            # per scan after any new optimisation, joins corrections that
            # come close together, so its count is no bound.)
            print("back-end optimisations offline: %d; loop_closed_path messages: %d" %
                  (optimisations, len(self.loop_paths)))
            self.assertLessEqual(len(runs), optimisations,
                                 "more disagreements than back-end optimisations")
            late_scans = math.ceil(LATE_CORRECTION_SECONDS * self.args.rate * scan_rate)
            print("a correction may arrive up to %.1f s late: %d scans at %.0fx, %.2f scans/s" %
                  (LATE_CORRECTION_SECONDS, late_scans, self.args.rate, scan_rate))
            self.assertLessEqual(max(runs or [0]), late_scans)


if __name__ == "__main__":
    main(LiveLoopReplay, "live_loop_replay", seconds=1000.0, rate=10.0,
         add_arguments=lambda parser: parser.add_argument("--correction-delay", type=int,
                                                          default=-1))
