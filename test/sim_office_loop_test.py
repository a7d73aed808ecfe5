#!/usr/bin/python3
"""Scores one simulated loop of the office world (test/sim_office_loop.test)
with tools/dev/sim_monitor.py and asserts its acceptance figures:
  - final position error < 0.10 m and heading error < 2 deg; mean error
    over the loop < 0.12 m, while odometry alone is at least 2x farther off
    (mean error; its largest > 0.2 m);
  - average pose NEES reported with its two-sided 95 % band (for the
    independent samples the run's own errors show, which one run
    overcounts); asserted only below 10 (see the comment in the test: one run's band is
    not a sound test; consistency is judged over seeds by
    tools/dev/office_monte_carlo.sh, docs/results.md "The pose NEES");
  - no landmark duplicated (two landmarks within 3 sigma of each other at the
    same true corner);
  - the live grid is on /map within 10 s of the robot moving, grows as it
    drives, and map_metadata equals the last grid's info;
and then replays the run's recording through offline.launch
(ekf_slam_tools.sim_replay.pause_and_replay): the offline outputs exist and the run is
reproduced (same landmarks, final pose within 1 cm), and the smoothed
trajectory (the full smoother) is at least as close to the truth as the
filtered one, or within the smoother's own spread (SMOOTHED_SPREAD).
"""
import argparse
import os
import sys
import unittest

import rostest

from ekf_slam_tools import sim_monitor, sim_replay

# m: the full smoother's mean error on office loops reaches up to this on
# its own (largest over seven recorded loops: 15.2 mm; on a machine with two
# busy loops beside the test, where the live run drops other scans, 24.9 mm
# against the filter's 15.8 mm); below it "not worse than the filter" is not
# resolved by one draw.
SMOOTHED_SPREAD = 0.03


class OfficeLoop(unittest.TestCase):
    def test_loop_against_ground_truth(self):
        argv = [a for a in sys.argv[1:] if not a.startswith("__") and not a.startswith("--gtest")]
        parser = argparse.ArgumentParser()
        parser.add_argument("--out", required=True)
        parser.add_argument("--world", default="office")
        parser.add_argument("--timeout", type=float, default=800.0)
        parser.add_argument("--slam-node", default="/ekf_slam")
        args, _ = parser.parse_known_args(argv)
        # sim_office_loop.test starts SLAM paused; it maps once the recorder listens.
        args.resume_after_recorder = "/office_loop_recorder"
        r = sim_monitor.run(args)  # rospy.init_node is done here
        print(sim_monitor.report_text(r))
        self.assertFalse(r["ended_early"], r["ended_early"])
        self.assertLess(r["final_position_error"], 0.10)
        self.assertLess(r["final_heading_error_deg"], 2.0)
        # Odometry is a random walk that may end near where it started: it is
        # judged over the whole loop (its mean error, and its largest above
        # 0.2 m), not at the end. SLAM's largest error is printed, not held
        # to a third of odometry's: before the loop closes it can spike in
        # some noise draws (a CI run of seed 1 on the earlier world with a
        # turned cabinet: 0.278 m against 0.464 m).
        # SLAM's mean error over the loop is held on its own (runs measured:
        # 0.012-0.088 m), and against odometry's at half of it. Odometry's
        # mean error depends on the noise draw and on the path driven
        # (0.24-0.55 m over recent CI runs): at a third, one run failed whose
        # odometry happened to stay close (0.240 m) while SLAM was as usual
        # (0.084 m; the same test passed again at 0.012 against 0.461 m).
        self.assertGreater(r["odometry_max_position_error"], 0.2)
        self.assertLess(r["mean_position_error"], 0.12)
        self.assertGreater(r["odometry_mean_position_error"], 2.0 * r["mean_position_error"])
        # One run's pose NEES is a weak test: much of its error lasts the
        # whole loop (over seeds a loop is worth about 2.4 independent
        # samples), so single runs scatter from 0.8 to 8 (docs/results.md). Consistency
        # is judged over seeds (tools/dev/office_monte_carlo.sh, docs/results.md
        # "The pose NEES"); here only a regression guard.
        self.assertLess(r["nees_average"], 10.0)
        self.assertEqual(len(r["duplicates"]), 0, "duplicated landmarks: %s" % r["duplicates"])
        self.assertGreater(r["landmarks_near_true_corners"], 10)
        # The live grid of the default simulation (loop closure off): on
        # `map` within 10 s of the robot moving, growing as it drives, with
        # map_metadata describing it.
        live = r["live_map"]
        self.assertIsNotNone(live["map_delay"], "no grid on /map after the robot moved")
        self.assertLess(live["map_delay"], 10.0)
        self.assertGreater(live["last_known_cells"], live["first_known_cells"])
        self.assertTrue(live["metadata_matches"], "map_metadata differs from the last map's info")

        bag = argv[argv.index("--bag") + 1]
        replay = sim_replay.pause_and_replay(self, os.path.join(args.out, "replay"),
                                                  "/office_loop_recorder", bag,
                                                  wait_for_done=False)
        self.assertEqual(replay["offline_landmarks"], replay["live_landmarks"])
        self.assertLess(replay["distance"], 0.01)
        # trajectory_smoothed.txt is the full smoother (batch MAP over
        # every pose, landmark and observation the filter used,
        # docs/maths.md 8b). Over seven recorded office loops (docs/offline.md,
        # "The full smoother on office loops") its mean error was 4.5-15.2 mm
        # whatever the filter's (10-80 mm): it has a floor of its own, about
        # 1 cm, so on a draw where the filter comes out near that floor the
        # two are level within their scatter (a CI draw: 14.9 mm smoothed
        # against 10.7 mm filtered). Asserted: not worse than the filter's,
        # unless within the smoother's own spread (SMOOTHED_SPREAD). The
        # thesis's pose-only RTS smoother (trajectory_rts.txt) is printed
        # only.
        print("full smoother / RTS / filter against the truth: %.4f / %.4f / %.4f m mean "
              "position error" % (replay["smoothed_error"], replay["rts_error"],
                                  replay["filtered_error"]))
        self.assertLessEqual(replay["smoothed_error"],
                             max(replay["filtered_error"] +
                                 sim_replay.smoothed_tolerance(replay["filtered_error"]),
                                 SMOOTHED_SPREAD))


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "sim_office_loop", OfficeLoop, sys.argv)
