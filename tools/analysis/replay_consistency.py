#!/usr/bin/python3
"""Consistency of the filter on a recorded simulator run, offline.

A live simulated loop gives one NEES figure per 2.5 minutes of real time; a
bag recorded from it (sim_office_loop.test and sim_replay.test record one)
can be replayed through ekf_slam_offline in seconds, deterministically, and
with different configurations. This script scores such a replay:
trajectory_filtered.txt and covariance_filtered.txt of the run against the
bag's /ground_truth/odom (map frame = the truth at the first scan, as
the monitor, ekf_slam_tools.sim_monitor, does), with the same 2 mm / 1 mrad truth allowance.

usage:
  replay_consistency.py --bag BAG [--bag BAG2 ...] --out DIR [--config YAML] [--runner EXE]
      runs ekf_slam_offline on each BAG into DIR/<n> (DIR itself for one
      bag; default config: config/ekf_slam_sim.yaml), then scores each run
  replay_consistency.py ... --no-run
      scores the runs already there

Prints, per run, the average pose NEES with its 95 % band for the effective
number of independent samples, the rms normalised error per axis (1.0
when the filter's sigma fits its errors) and the position error (mean,
largest, final), so that a change bought with accuracy shows. With several bags (recordings
with different noise seeds: tools/dev/office_monte_carlo.sh) it also prints the
Monte Carlo figure: the NEES averaged over all runs against the band the
runs' own spread gives, and what one run is worth in independent samples.
One office loop is worth only two or three (its errors against the start
last the whole loop), so one run's figure says little; the pooled figure
is the consistency test.
"""
import argparse
import math
import os
import subprocess
import sys

import numpy as np
import rosbag

from ekf_slam_tools import se2, stats
from ekf_slam_tools.sim_monitor import TRUTH_SIGMA
from ekf_slam_tools.trajectories import rows_by_stamp

HERE = os.path.dirname(os.path.abspath(__file__))


def read_truth(bag_path):
    truth = []
    with rosbag.Bag(bag_path) as bag:
        for _, msg, _ in bag.read_messages(topics=["/ground_truth/odom"]):
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            truth.append((msg.header.stamp.to_sec(), p.x, p.y, se2.yaw_of(q)))
    truth.sort()
    if len(truth) < 2:
        raise RuntimeError("%s has no /ground_truth/odom (not a simulator recording?)" % bag_path)
    return truth


def score(truth, run_dir):
    poses = rows_by_stamp(os.path.join(run_dir, "trajectory_filtered.txt"), 4)
    covariances = rows_by_stamp(os.path.join(run_dir, "covariance_filtered.txt"), 7)
    stamps = sorted(s for s in poses if s in covariances and
                    se2.interpolate(truth, s) is not None)
    if len(stamps) < 2:
        raise RuntimeError("%s: fewer than 2 scans overlap the ground truth" % run_dir)
    first = poses[stamps[0]][1:4]
    map_world = se2.inverse(
        se2.compose(se2.interpolate(truth, stamps[0]), se2.inverse(first)))
    allowance = np.diag(np.square(TRUTH_SIGMA))
    white, normalised, distances = [], [], []
    for s in stamps:
        est = poses[s][1:4]
        true = se2.compose(map_world, se2.interpolate(truth, s))
        e = np.array([est[0] - true[0], est[1] - true[1], se2.wrap(est[2] - true[2])])
        distances.append(math.hypot(e[0], e[1]))
        c = covariances[s][1:]
        cov = np.array([[c[0], c[1], c[2]], [c[1], c[3], c[4]], [c[2], c[4], c[5]]]) + allowance
        white.append(stats.whitened(e, cov))
        normalised.append(e / np.sqrt(np.diag(cov)))
    nees = [float(w @ w) for w in white]
    samples = stats.nees_effective_samples(white)
    band = stats.nees_band(3, samples)
    rms = np.sqrt(np.mean(np.square(normalised), axis=0))
    errors = (float(np.mean(distances)), max(distances), distances[-1])
    return np.mean(nees), len(nees), samples, band, rms, errors


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bag", required=True, action="append", help="repeat for several runs")
    parser.add_argument("--out", required=True)
    parser.add_argument("--config", default=os.path.join(HERE, "..", "..", "config", "ekf_slam_sim.yaml"))
    parser.add_argument("--runner", default="ekf_slam_offline",
                        help="path of ekf_slam_offline (default: found by rosrun)")
    parser.add_argument("--no-run", action="store_true")
    args = parser.parse_args()
    runner = [args.runner] if os.path.sep in args.runner else ["rosrun", "ekf_slam", args.runner]
    inverse_samples, means, all_errors = 0.0, [], []
    for n, bag in enumerate(args.bag):
        out = os.path.join(args.out, str(n)) if len(args.bag) > 1 else args.out
        if not args.no_run:
            os.makedirs(out, exist_ok=True)
            result = subprocess.run(runner + ["--bag", bag, "--out", out, "--config", args.config,
                                              "--no-figures"],
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            if result.returncode != 0:
                sys.exit("replay_consistency: ekf_slam_offline failed on %s (%d):\n%s" %
                         (bag, result.returncode, result.stdout[-2000:]))
        mean, count, samples, band, rms, errors = score(read_truth(bag), out)
        inside = band[0] <= mean <= band[1]
        print("%s: average pose NEES %.2f over %d scans (%.0f independent), 95%% band "
              "%.2f..%.2f: %s; rms normalised error x %.2f, y %.2f, heading %.2f; position "
              "error mean %.3f m, largest %.3f m, final %.3f m" %
              (bag, mean, count, samples, band[0], band[1], "inside" if inside else "outside",
               rms[0], rms[1], rms[2], errors[0], errors[1], errors[2]))
        means.append(mean)
        all_errors.append(errors)
        inverse_samples += 1.0 / samples
    if len(means) > 1:
        pooled = sum(means) / len(means)
        # The runs are independent draws of one loop's average NEES: their
        # spread shows how far one average strays, whatever the correlation
        # of the poses within a run (which one run cannot measure when part
        # of its error lasts the whole run). Consistent, their mean is 3.
        band = stats.runs_band(3.0, means)
        inside = band[0] <= pooled <= band[1]
        # What one run is worth: 6 / variance of its average, for chi-square(3).
        spread = float(np.var(means, ddof=1))
        print("Monte Carlo over %d runs: average pose NEES %.2f (runs from %.2f to %.2f), 95%% "
              "band %.2f..%.2f (3 +- t s / sqrt(runs)): %s; one run is worth about %.1f "
              "independent samples (the runs' own estimates: %.1f)" %
              (len(means), pooled, min(means), max(means), band[0], band[1],
               "inside" if inside else "outside", 6.0 / spread if spread > 0 else float("inf"),
               len(means) / inverse_samples))
        print("Monte Carlo over %d runs: position error mean %.3f m (runs' means), largest %.3f m, "
              "final at most %.3f m" % (len(means), np.mean([e[0] for e in all_errors]),
                                        max(e[1] for e in all_errors),
                                        max(e[2] for e in all_errors)))

if __name__ == "__main__":
    main()
