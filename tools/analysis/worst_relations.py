#!/usr/bin/python3
"""Where a trajectory's relation error comes from: the relations with the
largest translational error, and how much of the mean they carry.

  tools/analysis/worst_relations.py RELATIONS TRAJECTORY [--top N]

RELATIONS: a relations file (timestamp1 timestamp2 x y z roll pitch yaw,
the second pose seen from the first); TRAJECTORY: the offline runner's
trajectory file (stamp x y theta ...). Each relation's poses are the
trajectory's poses nearest in time (evaluate_relations gives the scores
themselves). Prints the mean, the share of the error the worst 1 / 5 /
10 / 20 / 50 relations carry with the mean without them, and the worst N
with their times from the log's first relation.
"""
import argparse
import bisect
import math


def read_trajectory(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append([float(v) for v in line.split()[:4]])
    rows.sort()
    return rows


def nearest(rows, stamps, t):
    k = bisect.bisect_left(stamps, t)
    candidates = [j for j in (k - 1, k) if 0 <= j < len(rows)]
    return rows[min(candidates, key=lambda j: abs(stamps[j] - t))]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("relations")
    parser.add_argument("trajectory")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args()
    rows = read_trajectory(args.trajectory)
    stamps = [r[0] for r in rows]
    errors = []
    with open(args.relations) as f:
        for line in f:
            if not line.strip() or line.startswith("#"):
                continue
            t1, t2, x, y = (float(v) for v in line.split()[:4])
            a, b = nearest(rows, stamps, t1), nearest(rows, stamps, t2)
            c, s = math.cos(a[3]), math.sin(a[3])
            dx, dy = b[1] - a[1], b[2] - a[2]
            error = math.hypot(c * dx + s * dy - x, -s * dx + c * dy - y)
            errors.append((error, t1, t2, math.hypot(x, y)))
    if not errors:
        raise SystemExit("worst_relations: no relation in %s" % args.relations)
    errors.sort(reverse=True)
    total = sum(e[0] for e in errors)
    print("%d relations, mean %.4f m" % (len(errors), total / len(errors)))
    for k in (1, 5, 10, 20, 50):
        if k < len(errors):
            worst = sum(e[0] for e in errors[:k])
            print("worst %2d: %4.1f %% of the error; mean without them %.4f m"
                  % (k, 100.0 * worst / total, (total - worst) / (len(errors) - k)))
    start = min(e[1] for e in errors)
    for error, t1, t2, length in errors[:args.top]:
        print("%7.2f m  t1 %7.0f s  t2 %7.0f s  relation %.1f m" % (error, t1 - start, t2 - start, length))


if __name__ == "__main__":
    main()
