#!/usr/bin/python3
"""~smooth during a real log's replay (test/smooth_during_replay.test).

Plays the first --seconds of the bag on /clock at --rate into slam.launch
and calls ~smooth three times while it plays, and on until one solve has
taken longer than MAX_PAUSE. ~smooth runs the full
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
import threading
import time

import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Path
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage

from ekf_slam_tools.replay_test import ReplayTest, main

MAX_PAUSE = 0.3  # s (wall) between two map -> odom messages while ~smooth runs
CALLS = 3
FIRST_CALL_AFTER = 2500  # poses published before the first call (a long history)


class SmoothDuringReplay(ReplayTest):
    def setUp(self):
        super().setUp()
        self.lock = threading.Lock()
        self.pose_stamps = set()
        self.map_to_odom_wall = []  # wall time of each map -> odom on /tf
        self.smoothed_paths = []  # pose counts of smoothed_path messages
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10000)
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=10000)
        rospy.Subscriber("smoothed_path", Path, self.on_smoothed_path, queue_size=10)

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

    def poses(self):
        with self.lock:
            return len(self.pose_stamps)

    def test_map_to_odom_flows_while_smoothing(self):
        self.wait_for_node("ekf_slam/smooth")
        smooth = rospy.ServiceProxy("ekf_slam/smooth", Trigger)
        player = self.player()
        calls = []  # (start, end, response)
        try:
            deadline = time.time() + 120.0
            while self.poses() < FIRST_CALL_AFTER and time.time() < deadline:
                time.sleep(0.1)
            self.assertGreaterEqual(self.poses(), FIRST_CALL_AFTER, "too few poses published")
            # At least CALLS calls, and on until one solve outlasts the pause
            # bound (the history grows as the log plays, and the solve with
            # it): a machine quick enough to solve every call sooner shows
            # nothing, and calling on while the log plays makes it show.
            longest = 0.0
            while (len(calls) < CALLS or longest <= MAX_PAUSE) and player.poll() is None:
                start = time.time()
                response = smooth()
                calls.append((start, time.time(), response))
                longest = max(longest, calls[-1][1] - start)
                time.sleep(1.0)
        finally:
            player.wait()
        self.settle(self.poses)  # the node finishes its queue
        time.sleep(2.0)  # one more /diagnostics

        self.assertGreaterEqual(len(calls), CALLS, "the log ended before %d calls" % CALLS)
        for start, end, response in calls:
            print("~smooth: %.3f s: %s" % (end - start, response.message))
            self.assertTrue(response.success, response.message)
        self.assertGreaterEqual(len(self.smoothed_paths), len(calls))
        self.assertGreaterEqual(min(self.smoothed_paths), FIRST_CALL_AFTER)

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
        received = self.diagnostics.count("scans received")
        waiting = self.diagnostics.count("scans waiting for transforms")
        drops = self.diagnostics.drops()
        print("played %d scans; received %d; poses %d; dropped %s; waiting %d" %
              (played, received, self.poses(), drops or "none", waiting))
        self.assertEqual(received, played)
        self.assertEqual(self.poses() + sum(drops.values()) + waiting, played)


if __name__ == "__main__":
    main(SmoothDuringReplay, "smooth_during_replay", seconds=800.0, rate=20.0)
