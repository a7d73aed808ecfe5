#!/usr/bin/python3
"""Scores one simulated loop of the office world (test/sim_office_loop.test)
with tools/sim_monitor.py and asserts the acceptance figures of issue 6:
  - final position error < 0.10 m and heading error < 2 deg, while odometry
    alone ends at least 3x farther off (and > 0.2 m);
  - average pose NEES inside its two-sided 95 % band (the band is computed
    for the number of independent samples the time-correlated series holds);
  - no landmark duplicated (two landmarks within 3 sigma of each other at the
    same true corner).
"""
import os
import sys
import unittest

import rospkg
import rostest

sys.path.insert(0, os.path.join(rospkg.RosPack().get_path("ekf_slam"), "tools"))
import sim_monitor  # noqa: E402


class OfficeLoop(unittest.TestCase):
    def test_loop_against_ground_truth(self):
        argv = [a for a in sys.argv[1:] if not a.startswith("__") and not a.startswith("--gtest")]
        parser = sim_monitor.argparse.ArgumentParser()
        parser.add_argument("--out", required=True)
        parser.add_argument("--world", default="office")
        parser.add_argument("--timeout", type=float, default=800.0)
        parser.add_argument("--slam-node", default="/ekf_slam")
        args, _ = parser.parse_known_args(argv)
        r = sim_monitor.run(args)
        print(sim_monitor.report_text(r))
        self.assertLess(r["final_position_error"], 0.10)
        self.assertLess(r["final_heading_error_deg"], 2.0)
        self.assertGreater(r["odometry_final_position_error"], 0.2)
        self.assertGreater(r["odometry_final_position_error"], 3.0 * r["final_position_error"])
        low, high = r["nees_band_95"]
        self.assertGreater(r["nees_average"], low)
        self.assertLess(r["nees_average"], high)
        self.assertEqual(len(r["duplicates"]), 0, "duplicated landmarks: %s" % r["duplicates"])
        self.assertGreater(r["landmarks_near_true_corners"], 10)


if __name__ == "__main__":
    rostest.rosrun("ekf_slam", "sim_office_loop", OfficeLoop, sys.argv)
