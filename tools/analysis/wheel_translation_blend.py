#!/usr/bin/python3
"""How much the wheels' short-range translation could add to a final
trajectory: a positions-only blend, computed after the fact.

  source .build/setup.bash
  tools/analysis/wheel_translation_blend.py RUN_DIR OUT [--sigma-wheel M]
      [--sigma-step M] [--sigma-anchor M] [--scale auto|S]
  evaluate_relations --relations ../shared/datasets/LOG.relations --trajectory OUT

RUN_DIR: an offline run (trajectory_smoothed.txt, trajectory_odometry.txt).
The headings stay the final trajectory's. The positions p_k minimise, per
coordinate,

  sum_k |p_k - p_{k-1} - f_k|^2 / sigma_step^2
      + |p_k - p_{k-1} - R(theta_{k-1}) s w_k|^2 / sigma_wheel^2
      + |p_k - P_k|^2 / sigma_anchor^2

with P the final positions, f_k their steps, w_k the wheels' step in the
robot frame (scans whose stamp does not increase, and odometry jumps over
0.5 m, carry no wheel term), theta the final headings and s the wheels'
distance scale. --scale auto takes s as the median, over blocks of 200
moving steps, of the final trajectory's forward travel over the wheels'
(a wheel radius a few per cent off is common). The system is tridiagonal
and solved in O(n). This is an analysis of what is there to gain, not a
part of the pipeline: sigma_wheel is a choice, and which value helps
depends on how good the log's wheels are against its scan matcher.
"""
import argparse
import math
import os

from ekf_slam_tools import se2
from ekf_slam_tools.trajectories import read_rows

MAX_WHEEL_STEP = 0.5  # m: a larger step between two scans is an odometry jump
SCALE_BLOCK = 200  # moving steps per block of the scale estimate


def robot_frame_steps(rows):
    """(forward, left) of each step, in the frame of the step's first pose."""
    return [se2.compose(se2.inverse(a[1:4]), b[1:4])[:2] for a, b in zip(rows, rows[1:])]


def median(values):
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def solve_tridiagonal(lower, diagonal, upper, rhs):
    """Thomas algorithm; lower[i] couples i to i-1, upper[i] i to i+1."""
    n = len(diagonal)
    c, d = [0.0] * n, [0.0] * n
    c[0] = upper[0] / diagonal[0]
    d[0] = rhs[0] / diagonal[0]
    for i in range(1, n):
        m = diagonal[i] - lower[i] * c[i - 1]
        c[i] = upper[i] / m if i < n - 1 else 0.0
        d[i] = (rhs[i] - lower[i] * d[i - 1]) / m
    x = [0.0] * n
    x[-1] = d[-1]
    for i in range(n - 2, -1, -1):
        x[i] = d[i] - c[i] * x[i + 1]
    return x


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("run_dir")
    parser.add_argument("out")
    parser.add_argument("--sigma-wheel", type=float, default=0.01, help="m per step")
    parser.add_argument("--sigma-step", type=float, default=0.005,
                        help="m per step, the final trajectory's steps")
    parser.add_argument("--sigma-anchor", type=float, default=0.05,
                        help="m, the final trajectory's positions")
    parser.add_argument("--scale", default="1", help="the wheels' distance scale, or auto")
    args = parser.parse_args()

    final = read_rows(os.path.join(args.run_dir, "trajectory_smoothed.txt"))
    wheels = read_rows(os.path.join(args.run_dir, "trajectory_odometry.txt"))
    if len(final) != len(wheels) or any(abs(f[0] - w[0]) > 1e-6 for f, w in zip(final, wheels)):
        raise SystemExit("%s: the two trajectories do not share their scans" % args.run_dir)
    n = len(final)
    wheel_steps = robot_frame_steps(wheels)
    final_steps = robot_frame_steps(final)
    usable = [final[k + 1][0] > final[k][0] and math.hypot(*wheel_steps[k]) < MAX_WHEEL_STEP
              for k in range(n - 1)]

    if args.scale == "auto":
        moving = [k for k in range(n - 1) if usable[k] and abs(wheel_steps[k][0]) > 0.01]
        ratios = []
        for start in range(0, len(moving) - SCALE_BLOCK + 1, SCALE_BLOCK):
            block = moving[start:start + SCALE_BLOCK]
            travelled = sum(wheel_steps[k][0] for k in block)
            if abs(travelled) > 1e-9:
                ratios.append(sum(final_steps[k][0] for k in block) / travelled)
        scale = median(ratios) if ratios else 1.0
        print("wheel distance scale (final / wheels): %.4f from %d blocks" % (scale, len(ratios)))
    else:
        scale = float(args.scale)

    w_step = 1.0 / args.sigma_step ** 2
    w_wheel = 1.0 / args.sigma_wheel ** 2
    w_anchor = 1.0 / args.sigma_anchor ** 2
    weights = [w_step + (w_wheel if usable[k] else 0.0) for k in range(n - 1)]
    diagonal = [w_anchor] * n
    for k, w in enumerate(weights):
        diagonal[k] += w
        diagonal[k + 1] += w
    lower = [0.0] + [-w for w in weights]
    upper = [-w for w in weights] + [0.0]

    blended = [list(r[:4]) for r in final]
    for axis in (0, 1):
        rhs = [final[k][1 + axis] * w_anchor for k in range(n)]
        for k in range(n - 1):
            c, s = math.cos(final[k][3]), math.sin(final[k][3])
            fx, fy = final[k + 1][1] - final[k][1], final[k + 1][2] - final[k][2]
            target = w_step * (fx if axis == 0 else fy)
            if usable[k]:
                wx, wy = scale * wheel_steps[k][0], scale * wheel_steps[k][1]
                target += w_wheel * (c * wx - s * wy if axis == 0 else s * wx + c * wy)
            rhs[k + 1] += target
            rhs[k] -= target
        for k, value in enumerate(solve_tridiagonal(lower, diagonal, upper, rhs)):
            blended[k][1 + axis] = value

    with open(args.out, "w") as f:
        for r in blended:
            f.write("%.6f %.6f %.6f %.6f\n" % tuple(r))
    print("%d poses, %d of %d steps with a wheel term, written to %s" %
          (n, sum(usable), n - 1, args.out))


if __name__ == "__main__":
    main()
