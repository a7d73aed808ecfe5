#!/usr/bin/python3
"""Scores an offline run of a simulator recording against its truth.

A recording of the simulator (sim_office_loop.test leaves
/tmp/ekf_slam_rostest_office_loop.bag; tools/dev/office_monte_carlo.sh
keeps one per seed) carries /ground_truth/odom. Run ekf_slam_offline on it,
with any configuration, then:

  score_sim_run.py --bag BAG --run DIR

prints, for every trajectory_*.txt in DIR, the mean, largest and final
position error and the final heading error against the truth, with the
map frame tied to the truth at the trajectory's first pose (as the
rostests score a live run). The truth is interpolated at each pose's stamp.
"""
import argparse
import glob
import math
import os
import sys

import rosbag

from ekf_slam_tools import se2, sim_replay


def read_truth(bag_path):
    truth = []
    with rosbag.Bag(bag_path) as bag:
        for _, msg, _ in bag.read_messages(topics=["/ground_truth/odom"]):
            p = msg.pose.pose
            truth.append((msg.header.stamp.to_sec(), p.position.x, p.position.y,
                          se2.yaw_of(p.orientation)))
    return truth


def score(rows, truth):
    """(mean, largest, final position error [m], final heading error [deg],
    poses scored) of a trajectory against the truth; None when no pose
    falls within the truth's time span."""
    errors, heading = sim_replay.position_errors(rows, truth)
    if not errors:
        return None
    return (sum(errors) / len(errors), max(errors), errors[-1], math.degrees(abs(heading)),
            len(errors))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bag", required=True, help="simulator recording with /ground_truth/odom")
    parser.add_argument("--run", required=True, help="ekf_slam_offline's output directory")
    args = parser.parse_args()
    truth = read_truth(args.bag)
    if not truth:
        print("score_sim_run: %s has no /ground_truth/odom" % args.bag, file=sys.stderr)
        return 2
    paths = sorted(glob.glob(os.path.join(args.run, "trajectory_*.txt")))
    if not paths:
        print("score_sim_run: no trajectory_*.txt in %s" % args.run, file=sys.stderr)
        return 2
    print("%-24s %9s %9s %9s %9s %6s" % ("trajectory", "mean [m]", "max [m]", "final [m]",
                                          "final [°]", "poses"))
    for path in paths:
        result = score(sim_replay.read_trajectory(path), truth)
        name = os.path.basename(path)[len("trajectory_"):-len(".txt")]
        if result is None:
            print("%-24s outside the truth's time span" % name)
        else:
            print("%-24s %9.3f %9.3f %9.3f %9.2f %6d" % ((name,) + result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
