#!/usr/bin/python3
"""A real log replayed fast beside two busy loops (test/replay_under_load.test).

Starts --busy-loops processes (2) that spin on the machine's cores, then
plays the first --seconds of the log at --rate into slam.launch (built-in
configuration).
Checks:
- no scan is dropped as "in the future", and no transform either: the
  node's clock lags the log, the odometry does not;
- every scan played was received, and got a pose or a counted drop (or
  still waits for its transforms when the log ends).
"""
import subprocess
import sys
import threading

import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped

from ekf_slam_tools.replay_test import ReplayTest, main

class ReplayUnderLoad(ReplayTest):
    def setUp(self):
        super().setUp()
        self.lock = threading.Lock()
        self.pose_stamps = set()
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10000)

    def on_pose(self, msg):
        with self.lock:
            self.pose_stamps.add(round(msg.header.stamp.to_sec(), 6))

    def poses(self):
        with self.lock:
            return len(self.pose_stamps)

    def test_no_scan_is_in_the_future(self):
        self.wait_for_node()
        busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                for _ in range(self.args.busy_loops)]
        try:
            self.play()
            self.settle(self.poses)
        finally:
            for p in busy:
                p.kill()
                p.wait()
        self.settle(self.poses)
        played = self.played_scans()
        values = self.diagnostics.values()
        self.assertTrue(values, "no /diagnostics from the node")
        received = int(values["scans received"])
        waiting = int(values["scans waiting for transforms"])
        drops = self.diagnostics.drops()
        tf_drops = self.diagnostics.drops(kind="dropped tf: ")
        print("played %d scans beside %d busy loops; received %d; poses %d; dropped %s; "
              "transforms dropped %s; waiting %d" % (played, self.args.busy_loops, received,
                                                     self.poses(),
                                                     drops or "none", tf_drops or "none", waiting))
        self.assertNotIn("stamp in the future", drops)
        self.assertNotIn("stamp in the future", tf_drops)
        self.assertEqual(received, played)
        self.assertEqual(self.poses() + sum(drops.values()) + waiting, played)


if __name__ == "__main__":
    main(ReplayUnderLoad, "replay_under_load", seconds=400.0, rate=20.0,
         add_arguments=lambda parser: parser.add_argument("--busy-loops", type=int, default=2))
