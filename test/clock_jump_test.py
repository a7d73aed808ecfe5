#!/usr/bin/python3
"""A bag played twice: the clock jumps back (test/clock_jump.test).

Plays the first --seconds of the bag, then plays it again, as rosbag play
-l loops it. Checks:
- the second pass is mapped: poses for nearly all its scans;
- /diagnostics keeps coming through both passes and after them (it runs on
  wall time);
- --mode new_map: the map at the end is a new map of the same log, not
  the first pass's with the second added; --mode continue: the first
  pass's landmarks are kept (the second pass adds at most a few).
"""
import threading
import time

import rospy
from ekf_slam.msg import LandmarkMap
from geometry_msgs.msg import PoseWithCovarianceStamped

from ekf_slam_tools.replay_test import ReplayTest, main


class ClockJump(ReplayTest):
    def setUp(self):
        super().setUp()
        self.lock = threading.Lock()
        self.current = 0
        self.landmarks = 0
        self.stamps = [[], []]  # of the poses received during each pass
        rospy.Subscriber("pose", PoseWithCovarianceStamped, self.on_pose, queue_size=10000)
        rospy.Subscriber("landmark_map", LandmarkMap, self.on_map, queue_size=10)

    def on_pose(self, msg):
        with self.lock:
            self.stamps[self.current].append(msg.header.stamp.to_sec())

    def on_map(self, msg):
        with self.lock:
            self.landmarks = len(msg.landmarks)

    def poses(self):
        with self.lock:
            return len(self.stamps[0]) + len(self.stamps[1])

    def test_the_second_pass_is_mapped(self):
        self.wait_for_node()
        scans = self.played_scans()
        start = time.time()
        self.play()
        self.settle(self.poses, period=1.5)  # the node finishes its queue
        first_landmarks = self.landmarks
        with self.lock:
            self.current = 1
        second_start = time.time()
        self.play()
        self.settle(self.poses, period=1.5)
        end_of_play = time.time()
        time.sleep(3.5)
        print("scans per pass %d; poses %s; landmarks after the first pass %d, at the end %d; "
              "dropped: %s; waiting for transforms at the end %d" %
              (scans, [len(p) for p in self.stamps], first_landmarks, self.landmarks,
               self.diagnostics.drops() or "none",
               self.diagnostics.count("scans waiting for transforms")))
        missing = sorted(set(self.stamps[0]) - set(self.stamps[1]))
        print("scans of the first pass without a pose in the second: %d, %s ... %s" %
              (len(missing), missing[:5], missing[-5:]))
        self.assertGreater(len(self.stamps[0]), 0.95 * scans)
        # The first scans after the jump lose their odometry with the tf
        # buffer, and the last few of the second pass may still wait for
        # theirs when the log ends.
        self.assertGreater(len(self.stamps[1]), 0.9 * scans,
                           "the second pass was not mapped")

        walls = self.diagnostics.walls()
        for a, b in ((start, second_start), (second_start, end_of_play),
                     (end_of_play, end_of_play + 3.5)):
            self.assertGreaterEqual(sum(1 for t in walls if a <= t <= b), 2,
                                    "no /diagnostics for %.1f s" % (b - a))

        self.assertGreater(first_landmarks, 10)
        if self.args.mode == "new_map":
            # A new map of (nearly) the same scans: neither the first map
            # with the second pass added, nor empty.
            self.assertLess(self.landmarks, 1.2 * first_landmarks, "the first map was kept")
            self.assertGreater(self.landmarks, 0.5 * first_landmarks, "no new map")
        else:
            self.assertGreaterEqual(self.landmarks, first_landmarks, "the first pass's map lost")
            self.assertLess(self.landmarks, 1.2 * first_landmarks,
                            "the second pass mapped the log again beside the first")


if __name__ == "__main__":
    main(ClockJump, "clock_jump", seconds=100.0, rate=10.0,
         add_arguments=lambda parser: parser.add_argument("--mode", default="new_map"))
