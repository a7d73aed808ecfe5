#!/usr/bin/python3
"""Loop closure that does not depend on small drift (test/bent_loop.test).

The ACES log's wheel odometry is bent by a constant heading bias
(tools/dev/bend_odometry.py, 1 deg per metre), so that the scan-matched track
comes back more than 10 m from where it left. ekf_slam_offline runs, with
the built-in configuration, on the bent and on the original log.

Checks: on the bent log the scan-matched track is more than 10 m off at
some return (the drift is real); loops are accepted there and the final
trajectory's error at those returns is below 1 m; the final trajectory's
mean relation error is within 10 % of the original log's.
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import unittest

import rostest

BIAS_DEGREES_PER_METRE = 1.0
LONG_RELATION = 100.0  # s: relations farther apart than this span a loop


def executable(name):
    return subprocess.check_output(["catkin_find", "--first-only", "--libexec", "ekf_slam",
                                    name]).decode().split()[0]


def load_trajectory(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                t, x, y, theta = map(float, line.split()[:4])
                rows.append((t, x, y, theta))
    return rows


def relation_errors(relations_path, trajectory):
    """(time apart, translational error) of every relation, nearest poses by stamp."""
    import bisect
    stamps = [r[0] for r in trajectory]

    def at(t):
        i = bisect.bisect_left(stamps, t)
        if i > 0 and (i == len(stamps) or abs(stamps[i - 1] - t) < abs(stamps[i] - t)):
            i -= 1
        return trajectory[i]

    errors = []
    with open(relations_path) as f:
        for line in f:
            if not line.strip() or line.startswith("#"):
                continue
            v = list(map(float, line.split()))
            a, b = at(v[0]), at(v[1])
            c, s = math.cos(a[3]), math.sin(a[3])
            dx, dy = b[1] - a[1], b[2] - a[2]
            ex, ey = c * dx + s * dy - v[2], -s * dx + c * dy - v[3]
            errors.append((v[1] - v[0], math.hypot(ex, ey)))
    return errors


class BentLoop(unittest.TestCase):
    args = None

    def setUp(self):
        for path in (self.args.bag, self.args.relations):
            if not os.path.exists(path):
                self.skipTest(path + " not found (the datasets live in ../shared/datasets)")

    def run_offline(self, bag, out):
        subprocess.check_call([executable("ekf_slam_offline"), "--bag", bag, "--out", out,
                               "--no-maps"], stdout=subprocess.DEVNULL)
        with open(os.path.join(out, "report.txt")) as f:
            report = f.read()
        loops = int(re.search(r"(\d+) loops accepted", report).group(1))
        final = relation_errors(self.args.relations,
                                load_trajectory(os.path.join(out, "trajectory_smoothed.txt")))
        front = relation_errors(self.args.relations,
                                load_trajectory(os.path.join(out, "trajectory_scan_matched.txt")))
        return loops, final, front

    def test_a_loop_far_beyond_the_drift_is_closed(self):
        work = tempfile.mkdtemp(prefix="bent_loop_")
        bent_bag = os.path.join(work, "bent.bag")
        subprocess.check_call([sys.executable, self.args.bender, self.args.bag, bent_bag,
                               "--degrees-per-metre", str(BIAS_DEGREES_PER_METRE)],
                              stdout=subprocess.DEVNULL)
        loops, final, front = self.run_offline(bent_bag, os.path.join(work, "bent"))
        _, final_original, _ = self.run_offline(self.args.bag, os.path.join(work, "original"))

        front_long = max(e for dt, e in front if dt > LONG_RELATION)
        final_long = max(e for dt, e in final if dt > LONG_RELATION)
        mean_bent = sum(e for _, e in final) / len(final)
        mean_original = sum(e for _, e in final_original) / len(final_original)
        print("bent log: scan-matched track up to %.2f m off at a return, %d loops accepted, "
              "final error at the returns up to %.3f m; final mean %.4f m (original log %.4f m)"
              % (front_long, loops, final_long, mean_bent, mean_original))
        self.assertGreater(front_long, 10.0, "the bend should carry the front end > 10 m off")
        self.assertGreater(loops, 0)
        self.assertLess(final_long, 1.0, "a return more than 10 m off was not closed")
        self.assertLessEqual(mean_bent, 1.1 * mean_original)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--bag", required=True)
    parser.add_argument("--relations", required=True)
    parser.add_argument("--bender", required=True)
    BentLoop.args, _ = parser.parse_known_args(rospy_free_argv())
    rostest.rosrun("ekf_slam", "bent_loop", BentLoop)


def rospy_free_argv():
    return [a for a in sys.argv[1:] if not a.startswith("__") and not a.startswith("--gtest")]


if __name__ == "__main__":
    main()
