#!/usr/bin/python3
"""Where a simulated run's errors come from, measured against the truth.

For recordings of the simulator (tools/dev/office_monte_carlo.sh,
sim_office_loop.test) and, for the sightings, their offline replays with
--trace (ekf_slam_offline writes association_trace.txt), this prints the
checks behind the consistency analysis in docs/results.md:

  odometry   heading random walk of /odom against /ground_truth/odom, in
             rad^2 per metre driven (windows of 0.5 m or 0.5 rad), to set
             against filter.motion_noise.rot_per_metre; and the time shift
             of /odom against the truth that best explains its heading
             increments (0 when the stamps are right).
  scans      (--scans, slow: ray-casts the world image at the true pose)
             the shift of the scan stamps against the truth that best
             explains the ranges, and the bearing offset that does, on
             straight and on turning scans (0 and 0 when the emulated
             LMS200 and its driver are right).
  sightings  (runs with an association_trace.txt) each matched sighting's
             map position from the TRUE pose, against the median of its
             landmark's sightings: mean normalised squared error per feature
             kind and range band (2 when the covariance the filter was given
             fits), and the correlation of consecutive sightings' whitened
             errors (0 when they are independent); and split by place:
             near an object turned against the world's raster (a staircase
             of cells) or elsewhere. Then the same sightings
             against the world's true corners (the vertices of its raster,
             within 4 cm of the median of a landmark's sightings; lines
             meeting across a gap, virtual corners, against that median):
             median and mean normalised squared error (1.39 and 2 for a
             fitting covariance), the share beyond the 99.9 % gate (the
             overconfident tail; 0.1 % if it fits), the mean error along and
             across the beam (0 without bias) and the lag-1 correlation.

usage:
  sim_error_sources.py --bag BAG [--run DIR] [--bag BAG2 [--run DIR2] ...]
                       [--world config/worlds/office.yaml] [--scans]
"""
import argparse
import collections
import math
import os
import sys

import numpy as np
import rosbag

from ekf_slam_tools import se2, worlds

HERE = os.path.dirname(os.path.abspath(__file__))
LASER_X = 0.16  # m, config/calibration.yaml (the simulator's mount)
GATE_999 = 13.816  # chi-square(2) 99.9 % quantile


def read_poses(bag_path, topic):
    out = []
    with rosbag.Bag(bag_path) as bag:
        for _, msg, _ in bag.read_messages(topics=[topic]):
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            yaw = se2.yaw_of(q)
            out.append((msg.header.stamp.to_sec(), p.x, p.y, yaw))
    out.sort()
    return out


def odometry_walk(pairs):
    """(path, turn, heading-error change) per window over all bags."""
    rows = []
    for odom, truth in pairs:
        samples = [(o, se2.interpolate(truth, o[0])) for o in odom]
        samples = [(o, t) for o, t in samples if t is not None]
        # interpolate() gives (x, y, theta)
        error = np.unwrap([o[3] - t[2] for o, t in samples])
        path, turn = [0.0], [0.0]
        for (_, a), (_, b) in zip(samples, samples[1:]):
            path.append(path[-1] + math.hypot(b[0] - a[0], b[1] - a[1]))
            turn.append(turn[-1] + abs(se2.wrap(b[2] - a[2])))
        i = 0
        for j in range(1, len(samples)):
            if path[j] - path[i] >= 0.5 or turn[j] - turn[i] >= 0.5:
                rows.append((path[j] - path[i], turn[j] - turn[i], error[j] - error[i]))
                i = j
    return rows


def odometry_shift(odom, truth, shifts):
    """rms mismatch of 0.5 s heading increments for each shift of /odom."""
    tt = np.array([t[0] for t in truth])
    ty = np.unwrap([t[3] for t in truth])
    ot = np.array([o[0] for o in odom])
    oy = np.unwrap([o[3] for o in odom])
    out = []
    for shift in shifts:
        shifted = np.interp(ot + shift, tt, ty)
        d = (oy[5:] - oy[:-5]) - (shifted[5:] - shifted[:-5])
        out.append(math.sqrt(float(np.mean(d * d))))
    return out


class RasterWorld:
    """The simulator's world image: occupied cells, ray casting and corners."""

    def __init__(self, world_yaml):
        self.occupied, self.res, self.ox, self.oy = worlds.read_world_grid(world_yaml)
        self.steps = np.arange(0.02, 8.0, 0.005)

    def cast(self, x, y, angles):
        """First occupied range along each angle from (x, y); nan for none within 8 m."""
        height, width = self.occupied.shape
        px = x + np.outer(np.cos(angles), self.steps)
        py = y + np.outer(np.sin(angles), self.steps)
        ix = np.floor((px - self.ox) / self.res).astype(int)
        iy = np.floor((py - self.oy) / self.res).astype(int)
        inside = (ix >= 0) & (iy >= 0) & (ix < width) & (iy < height)
        hit = np.zeros_like(inside)
        hit[inside] = self.occupied[iy[inside], ix[inside]]
        first = np.where(hit.any(1), hit.argmax(1), -1)
        return np.where(first >= 0, self.steps[np.maximum(first, 0)], np.nan)

    def corners(self):
        """World positions of the raster's corners: the grid vertices where the
        occupied region turns (one or three of the four cells around the vertex
        occupied, or two diagonal ones). These are the points the laser really
        sees as corners and jamb edges, 5 cm steps included."""
        padded = np.pad(self.occupied, 1).astype(int)
        # cells around vertex (i, j) of the grid: (i-1..i, j-1..j) in padded + 1
        a = padded[:-1, :-1]
        b = padded[:-1, 1:]
        c = padded[1:, :-1]
        d = padded[1:, 1:]
        count = a + b + c + d
        diagonal = (count == 2) & (a == d)
        rows, cols = np.nonzero((count == 1) | (count == 3) | diagonal)
        return np.column_stack((self.ox + cols * self.res, self.oy + rows * self.res))


def scan_residuals(bag_path, truth, world, shifts, offsets, every=12, turning_rate=0.2):
    """Median |measured - ray-cast range| per scan-stamp shift (s) and per
    bearing offset (rad), ray-cast from the true pose. Returns (by shift,
    by offset on straight scans, by offset on scans turning faster than
    turning_rate rad/s, all of every fourth), each averaged over the scans used."""
    by_shift, straight, turning = np.zeros(len(shifts)), np.zeros(len(offsets)), np.zeros(len(offsets))
    counts = [0, 0, 0]
    with rosbag.Bag(bag_path) as bag:
        for k, (_, msg, _) in enumerate(bag.read_messages(topics=["/scan"])):
            # turning scans are few: all of every fourth scan; the others every `every`
            if k % 4:
                continue
            stamp = msg.header.stamp.to_sec()
            before = se2.interpolate(truth, stamp - 0.1)
            after = se2.interpolate(truth, stamp + 0.1)
            if before is None or after is None:
                continue
            rate = abs(se2.wrap(after[2] - before[2])) / 0.2
            if rate <= turning_rate and k % every:
                continue
            ranges = np.array(msg.ranges)
            angles = msg.angle_min + msg.angle_increment * np.arange(len(ranges))
            good = np.isfinite(ranges) & (ranges > 0.1) & (ranges < 7.5)

            cache = {}

            def residual(shift, offset):
                if (shift, offset) not in cache:
                    cache[(shift, offset)] = cast_residual(shift, offset)
                return cache[(shift, offset)]

            def cast_residual(shift, offset):
                pose = se2.interpolate(truth, stamp + shift)
                if pose is None:
                    return None
                lx = pose[0] + LASER_X * math.cos(pose[2])
                ly = pose[1] + LASER_X * math.sin(pose[2])
                d = ranges[good] - world.cast(lx, ly, pose[2] + offset + angles[good])
                d = d[np.isfinite(d) & (np.abs(d) < 0.1)]
                return float(np.median(np.abs(d))) if len(d) else None

            if k % every == 0:
                row = [residual(shift, 0.0) for shift in shifts]
                if all(v is not None for v in row):
                    by_shift += row
                    counts[0] += 1
            row = [residual(0.0, offset) for offset in offsets]
            if all(v is not None for v in row):
                if rate > turning_rate:
                    turning += row
                    counts[2] += 1
                else:
                    straight += row
                    counts[1] += 1
    return (by_shift / max(counts[0], 1), straight / max(counts[1], 1),
            turning / max(counts[2], 1), counts)


def turned_segments(world_yaml):
    """The world's segments that are neither horizontal nor vertical (objects
    turned against the raster), from ekf_slam_tools.worlds; [] if unknown."""
    name = os.path.splitext(os.path.basename(world_yaml))[0]
    if name not in worlds.WORLDS:
        return []
    return [(a, b) for a, b in worlds.WORLDS[name]()[0]
            if abs(a[0] - b[0]) > 1e-9 and abs(a[1] - b[1]) > 1e-9]


def distance_to_segments(p, segments):
    best = float("inf")
    for a, b in segments:
        d = np.subtract(b, a)
        t = min(1.0, max(0.0, float(np.dot(np.subtract(p, a), d) / np.dot(d, d))))
        best = min(best, math.hypot(*(np.add(a, t * d) - p)))
    return best


def matched_sightings(truth, run):
    """Each matched sighting of a replay's association_trace.txt, placed in
    the world from the TRUE pose: (landmark id, kind, position, covariance
    (2x2, world frame), world bearing of the beam, range)."""
    with open(os.path.join(run, "association_trace.txt")) as f:
        for line in f:
            if line.startswith("#"):
                continue
            v = line.split()
            if len(v) < 13:
                raise RuntimeError("%s: association_trace.txt without the kind and covariance "
                                   "columns (an older ekf_slam_offline)" % run)
            if v[6] != "matched":
                continue
            stamp, r, b = float(v[0]), float(v[4]), float(v[5])
            pose = se2.interpolate(truth, stamp)
            if pose is None:
                continue
            a = pose[2] + b
            lx = pose[0] + LASER_X * math.cos(pose[2])
            ly = pose[1] + LASER_X * math.sin(pose[2])
            J = np.array([[math.cos(a), -r * math.sin(a)], [math.sin(a), r * math.cos(a)]])
            rb = np.array([[float(v[10]), float(v[11])], [float(v[11]), float(v[12])]])
            yield (int(v[7]), v[9], np.array([lx + r * math.cos(a), ly + r * math.sin(a)]),
                   J @ rb @ J.T, a, r)


def sightings(bag_truth_runs, turned=(), near=0.5):
    """Normalised errors of matched sightings against the median of their
    landmark's sightings: per (kind, range band), and per (kind, whether the
    landmark lies within `near` of a turned segment)."""
    bands = ((0.0, 1.0, "<1 m"), (1.0, 2.0, "1-2 m"), (2.0, 4.0, "2-4 m"), (4.0, 1e9, ">4 m"))
    by_band = collections.defaultdict(list)
    by_place = collections.defaultdict(list)
    consecutive = collections.defaultdict(list)
    for truth, run in bag_truth_runs:
        per_landmark = collections.defaultdict(list)
        for landmark, kind, position, covariance, _, r in matched_sightings(truth, run):
            per_landmark[landmark].append((position, covariance, kind, r))
        for seen in per_landmark.values():
            if len(seen) < 8:
                continue
            reference = np.median(np.array([s[0] for s in seen]), axis=0)
            at_turned = distance_to_segments(reference, turned) < near
            whitened = []
            for position, covariance, kind, r in seen:
                e = position - reference
                d2 = float(e @ np.linalg.solve(covariance, e))
                band = next(name for lo, hi, name in bands if lo <= r < hi)
                by_band[(kind, band)].append(d2)
                by_place[(kind, at_turned)].append(d2)
                whitened.append(np.linalg.cholesky(np.linalg.inv(covariance)).T @ e)
            for u, w in zip(whitened, whitened[1:]):
                consecutive[seen[0][2]].append(float(u @ w) / 2.0)
    return by_band, by_place, consecutive


def true_corner_errors(bag_truth_runs, corners, snap=0.04):
    """Matched sightings against the world's true raster corners. A
    landmark's true corner is the raster corner nearest the median of its
    sightings (from the true pose), if within snap: landmarks farther from
    every raster corner are lines meeting across a gap (a virtual corner)
    and are scored apart, against the median of their sightings. Per kind:
    each sighting's squared Mahalanobis distance (its own covariance) to the
    true corner, its error along and across the beam, and the correlation
    of consecutive sightings' whitened errors."""
    out = collections.defaultdict(lambda: {"d2": [], "along": [], "across": [], "pairs": []})
    for truth, run in bag_truth_runs:
        per_landmark = collections.defaultdict(list)
        for landmark, kind, position, covariance, a, _ in matched_sightings(truth, run):
            per_landmark[(landmark, kind)].append((position, covariance, a))
        for (_, kind), seen in per_landmark.items():
            median = np.median(np.array([s[0] for s in seen]), axis=0)
            distance = np.hypot(corners[:, 0] - median[0], corners[:, 1] - median[1])
            k = int(np.argmin(distance))
            virtual = distance[k] > snap
            reference = median if virtual else corners[k]
            result = out[(kind, virtual)]
            previous = None
            for position, covariance, a in seen:
                e = position - reference
                result["d2"].append(float(e @ np.linalg.solve(covariance, e)))
                result["along"].append(float(e @ [math.cos(a), math.sin(a)]))
                result["across"].append(float(e @ [-math.sin(a), math.cos(a)]))
                whitened = np.linalg.cholesky(np.linalg.inv(covariance)).T @ e
                if previous is not None:
                    result["pairs"].append((previous, whitened))
                previous = whitened
    return out


def lag_correlation(pairs):
    """Normalised correlation of consecutive whitened errors (0: independent)."""
    if not pairs:
        return float("nan")
    u = np.array([p[0] for p in pairs])
    w = np.array([p[1] for p in pairs])
    return float(np.sum(u * w) / math.sqrt(np.sum(u * u) * np.sum(w * w)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bag", action="append", required=True)
    parser.add_argument("--run", action="append", default=[],
                        help="offline replay of the bag before it, made with --trace")
    parser.add_argument("--world", default=os.path.join(HERE, "..", "..", "config", "worlds",
                                                        "office.yaml"))
    parser.add_argument("--scans", action="store_true",
                        help="ray-cast the world at the true pose (slow): stamp shift, bearing "
                        "offset")
    args = parser.parse_args()
    if args.run and len(args.run) != len(args.bag):
        sys.exit("sim_error_sources: give one --run per --bag (or none)")

    pairs, truths = [], []
    for bag in args.bag:
        truth = read_poses(bag, "/ground_truth/odom")
        if len(truth) < 2:
            sys.exit("sim_error_sources: %s has no /ground_truth/odom" % bag)
        truths.append(truth)
        pairs.append((read_poses(bag, "/odom"), truth))

    rows = odometry_walk(pairs)
    straight = [r for r in rows if r[1] < 0.05]
    if straight:
        rate = np.mean([r[2] ** 2 for r in straight]) / np.mean([r[0] for r in straight])
        print("odometry: heading random walk %.2e rad^2/m over %d straight 0.5 m windows" %
              (rate, len(straight)))
    shifts = [-0.1, -0.05, -0.02, -0.01, 0.0, 0.01, 0.02, 0.05, 0.1]
    mismatch = np.mean([odometry_shift(o, t, shifts) for o, t in pairs], axis=0)
    print("odometry: stamp shift against the truth that fits best %+.2f s (rms heading-increment "
          "mismatch %.3f deg there, %.3f deg at 0)" %
          (shifts[int(np.argmin(mismatch))], math.degrees(mismatch.min()),
           math.degrees(mismatch[shifts.index(0.0)])))
    world = RasterWorld(args.world) if args.scans or args.run else None
    if args.scans:
        offsets = [-0.004, -0.002, -0.001, 0.0, 0.001, 0.002, 0.004]
        results = [scan_residuals(b, t, world, shifts, offsets) for b, t in zip(args.bag, truths)]
        residual = np.mean([r[0] for r in results], axis=0)
        print("scans: stamp shift against the truth that fits best %+.2f s (median range residual "
              "%.4f m there, %.4f m at 0)" % (shifts[int(np.nanargmin(residual))],
                                             np.nanmin(residual), residual[shifts.index(0.0)]))
        for name, column, count in (("straight", 1, 1), ("turning", 2, 2)):
            residual = np.mean([r[column] for r in results], axis=0)
            scans = sum(r[3][count] for r in results)
            print("scans: bearing offset that fits best on %d %s scans %+.1f mrad (median range "
                  "residual %.4f m there, %.4f m at 0)" %
                  (scans, name, 1e3 * offsets[int(np.nanargmin(residual))], np.nanmin(residual),
                   residual[offsets.index(0.0)]))
    if args.run:
        by_band, by_place, consecutive = sightings(list(zip(truths, args.run)),
                                                   turned_segments(args.world))
        order = ["<1 m", "1-2 m", "2-4 m", ">4 m"]
        for key in sorted(by_band, key=lambda k: (k[0], order.index(k[1]))):
            v = by_band[key]
            print("sightings: %-10s %-6s %6d, mean normalised squared error %.2f (2 if the "
                  "covariance fits)" % (key[0], key[1], len(v), np.mean(v)))
        for (kind, at_turned), v in sorted(by_place.items()):
            v = np.array(v)
            print("sightings: %-10s %s: %d, mean normalised squared error %.2f (2), %.2f %% beyond "
                  "the 99.9 %% gate (0.1 %%)" %
                  (kind, "within 0.5 m of an object turned against the raster" if at_turned
                   else "elsewhere", len(v), np.mean(v), 100.0 * np.mean(v > GATE_999)))
        corners = world.corners()
        for (kind, virtual), r in sorted(true_corner_errors(list(zip(truths, args.run)),
                                                            corners).items()):
            d2 = np.array(r["d2"])
            print("sightings: %-10s %s: %d, normalised squared error median %.2f, mean %.2f "
                  "(1.39 and 2 if the covariance fits), %.2f %% beyond the 99.9 %% gate (0.1 %%), "
                  "mean error along the beam %+.1f mm, across %+.1f mm, consecutive whitened errors "
                  "correlate %.2f" %
                  (kind, "of virtual corners (lines meeting across a gap), against their median"
                   if virtual else "against the true raster corners", len(d2), np.median(d2),
                   np.mean(d2), 100.0 * np.mean(d2 > GATE_999), 1e3 * np.mean(r["along"]),
                   1e3 * np.mean(r["across"]), lag_correlation(r["pairs"])))
        for kind in sorted(consecutive):
            print("sightings: %-10s consecutive whitened errors correlate %.2f (%d pairs)" %
                  (kind, np.mean(consecutive[kind]), len(consecutive[kind])))


if __name__ == "__main__":
    main()
