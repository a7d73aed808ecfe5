#!/usr/bin/python3
"""Where a trajectory's relation error comes from: the relations with the
largest translational error, and how much of the mean they carry.

  source .build/setup.bash
  tools/analysis/worst_relations.py RELATIONS TRAJECTORY [--top N] [--tolerance S]

RELATIONS: a relations file (timestamp1 timestamp2 x y z roll pitch yaw,
the second pose seen from the first); TRAJECTORY: the offline runner's
trajectory file (stamp x y theta ...). As in evaluate_relations (which
gives the scores themselves), each relation takes the trajectory's poses
nearest its two stamps, within --tolerance; a relation without them is
left out and counted. Prints the mean, the share of the error the worst
1 / 5 / 10 / 20 / 50 relations carry with the mean without them, and the
worst N with their times from the log's first relation. With --local S,
also the error of the relations under S seconds apart (and over 0.2 m
long) split along each relation's own direction and across it (medians of
the absolute values): an error along the path that every trajectory
shares, the raw odometry too, is one no scan fixed.
"""
import argparse
import bisect
import math
import statistics

from ekf_slam_tools import se2
from ekf_slam_tools.trajectories import read_rows


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("relations")
    parser.add_argument("trajectory")
    parser.add_argument("--top", type=int, default=25)
    parser.add_argument("--tolerance", type=float, default=1e-4,
                        help="s, a pose farther from a relation's stamp is not its pose "
                             "(evaluate_relations' default)")
    parser.add_argument("--local", type=float, default=0.0,
                        help="s: split the error of the relations this close in time along "
                             "and across their direction (0: not)")
    args = parser.parse_args()
    rows = sorted(read_rows(args.trajectory))
    stamps = [r[0] for r in rows]

    def pose_at(t):
        k = bisect.bisect_left(stamps, t)
        near = min((j for j in (k - 1, k) if 0 <= j < len(rows)),
                   key=lambda j: abs(stamps[j] - t), default=None)
        if near is None or abs(stamps[near] - t) > args.tolerance:
            return None
        return tuple(rows[near][1:4])

    errors = []
    along, across = [], []  # |error| along / across short relations (--local)
    missing = 0
    for t1, t2, x, y, *_ in read_rows(args.relations):
        a, b = pose_at(t1), pose_at(t2)
        if a is None or b is None:
            missing += 1
            continue
        d = se2.compose(se2.inverse(a), b)
        ex, ey = d[0] - x, d[1] - y
        length = math.hypot(x, y)
        errors.append((math.hypot(ex, ey), t1, t2, length))
        if abs(t2 - t1) < args.local and length > 0.2:
            along.append(abs(ex * x + ey * y) / length)
            across.append(abs(x * ey - y * ex) / length)
    if not errors:
        raise SystemExit("worst_relations: no relation of %s finds its poses in %s"
                         % (args.relations, args.trajectory))
    errors.sort(reverse=True)
    total = sum(e[0] for e in errors)
    print("%d relations, mean %.4f m" % (len(errors), total / len(errors))
          + ("; %d left out (no pose within %g s)" % (missing, args.tolerance) if missing else ""))
    for k in (1, 5, 10, 20, 50):
        if k < len(errors):
            worst = sum(e[0] for e in errors[:k])
            print("worst %2d: %4.1f %% of the error; mean without them %.4f m"
                  % (k, 100.0 * worst / total, (total - worst) / (len(errors) - k)))
    if along:
        print("%d relations under %g s apart: error along them median %.4f m, across %.4f m"
              % (len(along), args.local, statistics.median(along), statistics.median(across)))
    start = min(e[1] for e in errors)
    for error, t1, t2, length in errors[:args.top]:
        print("%7.2f m  t1 %7.0f s  t2 %7.0f s  relation %.1f m" % (error, t1 - start, t2 - start, length))


if __name__ == "__main__":
    main()
