#!/usr/bin/python3
"""~smooth during a real log's replay (test/smooth_during_replay.test).

Plays the first --seconds of the bag on /clock at --rate into slam.launch
and calls ~smooth three times while it plays. ~smooth runs the full
smoother over every scan so far, a solve of a second or more on a long log;
the node runs it off the thread that takes the scans and publishes tf.

Checks:
- map -> odom keeps arriving on /tf while the solves run: between the first
  call and the end of the last, no two arrivals are MAX_PAUSE or more apart
  (wall clock), although at least one solve took longer than that;
- each call succeeded and published a smoothed path;
- every scan the log played was received, and got a pose or a counted drop
  (or still waits for its transforms when the log ends).
"""
import argparse
import os
import subprocess
import sys
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Path
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage

MAX_PAUSE = 0.3  # s (wall) between two map -> odom messages while ~smooth runs
CALLS = 3
FIRST_CALL_AFTER = 2500  # poses published before the first call (a long history)


class SmoothDuringReplay(unittest.TestCase):
    args = None

    def setUp(self):
        if not os.path.exists(self.args.bag):
            self.skipTest(self.args.bag + " not found (the datasets live in ../shared/datasets)")
        self.lock = threading.Lock()
        self.pose_stamps = set()
        self.map_to_odom_wall = []  # wall time of each map -> odom on /tf
        self.smoothed_paths = []  # pose counts of smoothed_path messages
        self.diagnostics = {}  # the last value of each key
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10000)
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=10000)
        rospy.Subscriber("smoothed_path", Path, self.on_smoothed_path, queue_size=10)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=100)

    def on_pose(self, msg):
        with self.lock:
            self.pose_stamps.add(round(msg.header.stamp.to_sec(), 6))

    def on_tf(self, msg):
        now = time.time()
        for t in msg.transforms:
            if t.header.frame_id == "map" and t.child_frame_id == "odom":
                with self.lock:
                    self.map_to_odom_wall.append(now)

    def on_smoothed_path(self, msg):
        with self.lock:
            self.smoothed_paths.append(len(msg.poses))

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                for kv in status.values:
                    self.diagnostics[kv.key] = kv.value

    def poses(self):
        with self.lock:
            return len(self.pose_stamps)

    def played_scans(self):
        """The scans `rosbag play -u seconds` plays: bag time before start + seconds."""
        with rosbag.Bag(self.args.bag) as bag:
            end = bag.get_start_time() + self.args.seconds
            return sum(1 for _, _, t in bag.read_messages(topics=["/scan"]) if t.to_sec() <= end)

    def test_map_to_odom_flows_while_smoothing(self):
        deadline = time.time() + 30.0
        while rospy.get_param("/use_sim_time", False) is not True and time.time() < deadline:
            time.sleep(0.1)
        rospy.wait_for_service("ekf_slam/smooth", timeout=60.0)
        smooth = rospy.ServiceProxy("ekf_slam/smooth", Trigger)
        player = subprocess.Popen(["rosbag", "play", "--clock", "--quiet", "-r",
                                   str(self.args.rate), "-u", str(self.args.seconds),
                                   self.args.bag])
        calls = []  # (start, end, response)
        try:
            deadline = time.time() + 120.0
            while self.poses() < FIRST_CALL_AFTER and time.time() < deadline:
                time.sleep(0.1)
            self.assertGreaterEqual(self.poses(), FIRST_CALL_AFTER, "too few poses published")
            while len(calls) < CALLS and player.poll() is None:
                start = time.time()
                response = smooth()
                calls.append((start, time.time(), response))
                time.sleep(1.0)
        finally:
            player.wait()
        # The node finishes its queue.
        last = -1
        while self.poses() != last:
            last = self.poses()
            time.sleep(2.0)
        time.sleep(2.0)  # one more /diagnostics

        self.assertEqual(len(calls), CALLS, "the log ended before %d calls" % CALLS)
        for start, end, response in calls:
            print("~smooth: %.3f s: %s" % (end - start, response.message))
            self.assertTrue(response.success, response.message)
        self.assertGreaterEqual(len(self.smoothed_paths), CALLS)
        self.assertGreater(min(self.smoothed_paths), FIRST_CALL_AFTER)

        # map -> odom while the solves ran.
        first, last_end = calls[0][0], calls[-1][1]
        arrivals = [t for t in self.map_to_odom_wall if first - 1.0 <= t <= last_end + 1.0]
        self.assertGreater(len(arrivals), 10, "map -> odom did not flow during the calls")
        pauses = [b - a for a, b in zip(arrivals, arrivals[1:])]
        longest_call = max(end - start for start, end, _ in calls)
        print("map -> odom: %d messages during %.1f s of calls, longest pause %.3f s; "
              "longest call %.3f s" % (len(arrivals), last_end - first, max(pauses), longest_call))
        self.assertGreater(longest_call, MAX_PAUSE,
                           "every solve was shorter than the pause bound: nothing shown")
        self.assertLess(max(pauses), MAX_PAUSE)

        # Every scan answered or counted.
        played = self.played_scans()
        d = self.diagnostics
        received = int(d["scans received"])
        waiting = int(d["scans waiting for transforms"])
        drops = {k[len("dropped: "):]: int(v) for k, v in d.items()
                 if k.startswith("dropped: ") and int(v) > 0}
        print("played %d scans; received %d; poses %d; dropped %s; waiting %d" %
              (played, received, self.poses(), drops or "none", waiting))
        self.assertEqual(received, played)
        self.assertEqual(self.poses() + sum(drops.values()) + waiting, played)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--bag", required=True)
    parser.add_argument("--seconds", type=float, default=700.0)
    parser.add_argument("--rate", type=float, default=20.0)
    args, _ = parser.parse_known_args(rospy.myargv(sys.argv)[1:])
    SmoothDuringReplay.args = args
    rospy.init_node("smooth_during_replay_test")
    rostest.rosrun("ekf_slam", "smooth_during_replay", SmoothDuringReplay)
