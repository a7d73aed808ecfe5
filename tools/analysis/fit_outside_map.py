#!/usr/bin/python3
"""Where the scans that do not fit a saved map were taken.

ekf_slam_offline --resume STATE --localize-only writes fit_to_saved_map.txt
(each scan's fit to the saved map near its causal pose). This tells, for
the scans that fit under the lost threshold, how far each was taken from
the path the saved run drove (a trajectory of the whole log, say the one
run's trajectory_smoothed.txt, cut at the first stamp of the fit file): a
scan far from that path was taken where the saved map cannot explain it,
a scan on it where the map should.

  fit_outside_map.py FIT_FILE TRAJECTORY [--threshold 0.3] [--near 1.0]

Prints one line: the scans under the threshold, how many of them lie
farther than --near metres from the saved run's path, and the median
distance.
"""
import argparse
import bisect
import math
import sys
from collections import defaultdict


def read_rows(path, columns):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            rows.append(tuple(float(v) for v in line.split()[:columns]))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("fit")
    parser.add_argument("trajectory")
    parser.add_argument("--threshold", type=float, default=0.3)
    parser.add_argument("--near", type=float, default=1.0)
    args = parser.parse_args()
    fit = read_rows(args.fit, 2)
    path = read_rows(args.trajectory, 3)
    if not fit or not path:
        sys.exit("fit_outside_map: an empty input")
    saved_until = fit[0][0]
    cell = 2.0
    saved = defaultdict(list)  # the saved run's positions, hashed by cell
    for t, x, y in path:
        if t < saved_until:
            saved[(math.floor(x / cell), math.floor(y / cell))].append((x, y))
    stamps = [p[0] for p in path]

    def distance_to_saved(x, y):
        # Up to `reach` cells around: farther counts as far.
        reach = 5
        cx, cy = math.floor(x / cell), math.floor(y / cell)
        best = reach * cell
        for dx in range(-reach, reach + 1):
            for dy in range(-reach, reach + 1):
                for a, b in saved.get((cx + dx, cy + dy), ()):
                    best = min(best, math.hypot(a - x, b - y))
        return best

    distances = []
    for stamp, value in fit:
        if value >= args.threshold:
            continue
        i = min(bisect.bisect_left(stamps, stamp), len(stamps) - 1)
        distances.append(distance_to_saved(path[i][1], path[i][2]))
    distances.sort()
    far = sum(d > args.near for d in distances)
    median = distances[len(distances) // 2] if distances else float("nan")
    median_text = ("%.0f m or more" % (5 * cell)) if median >= 5 * cell else "%.1f m" % median
    print("%d of %d scans fit under %.2f; %d of them farther than %.1f m from the saved run's "
          "path (median %s)" % (len(distances), len(fit), args.threshold, far, args.near,
                                median_text))


if __name__ == "__main__":
    main()
