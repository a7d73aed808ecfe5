#!/usr/bin/python3
"""Plots the line-feature experiment (tools/dev/line_experiment.cc), the
equivalents of the thesis's Figs. 4.1-4.4, and compares the variants run by
run.

usage: tools/analysis/plot_line_experiment.py DIR
Reads DIR/summary.txt, DIR/runs.txt, DIR/world.txt and per variant V
DIR/V.txt, DIR/V_path.txt, DIR/V_map.txt. Writes DIR/line_experiment.png
(pose error, heading error, point feature error and average pose NEES with
its 95 % band over time), DIR/line_experiment_map.png (run 0: paths and
maps) and DIR/comparison.txt (paired differences between variants: every
variant sees the same odometry and point noise for a given seed).
"""
import argparse
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# The thesis's colours: red points only, green (p, θ) lines, blue θ-only lines.
STYLE = {
    "points": ("tab:red", "points only"),
    "ptheta_lines": ("tab:green", "points + (p, θ) lines"),
    "theta_lines": ("tab:blue", "points + θ lines (ends as points)"),
    "theta_lines_no_ends": ("tab:gray", "points + θ lines, no ends"),
    "points_360": ("tab:orange", "points, 360°"),
    "points_mecp_360": ("tab:purple", "points by MECP association, 360°"),
}


def read_summary(path):
    header, rows = None, []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                header = line[1:].split()
            elif line.strip():
                rows.append(dict(zip(header, line.split())))
    return rows


def read_runs(path):
    runs = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            name, _seed, mean_pos, final_pos, mean_point = line.split()[:5]
            runs.setdefault(name, []).append(
                (float(mean_pos), float(final_pos), float(mean_point)))
    return {k: np.array(v) for k, v in runs.items()}


def read_tagged(path):
    out = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            tag, *values = line.split()
            out.setdefault(tag, []).append([float(v) for v in values])
    return out


def plot_errors(directory, variants, band, out_path):
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    for name in variants:
        d = np.loadtxt(os.path.join(directory, name + ".txt"), ndmin=2)
        color, label = STYLE.get(name, ("black", name))
        t = d[:, 1]
        axes[0][0].plot(t, d[:, 2], color=color, label=label, linewidth=1)
        axes[0][1].plot(t, np.degrees(d[:, 3]), color=color, label=label, linewidth=1)
        axes[1][0].plot(t, d[:, 5], color=color, label=label, linewidth=1)
        axes[1][1].plot(t, d[:, 4], color=color, label=label, linewidth=0.8)
    axes[0][0].set_ylabel("position error (m)")
    axes[0][0].set_title("pose error (Fig. 4.3)")
    axes[0][1].set_ylabel("heading error (°)")
    axes[0][1].set_title("heading error")
    axes[1][0].set_ylabel("mean point feature error (m)")
    axes[1][0].set_title("feature error (Fig. 4.4)")
    ax = axes[1][1]
    ax.axhline(band[0], color="black", linestyle="--", linewidth=0.8)
    ax.axhline(band[1], color="black", linestyle="--", linewidth=0.8,
               label="95 %% band, %d runs" % band[2])
    ax.axhline(3.0, color="black", linewidth=0.5)
    ax.set_ylabel("average pose NEES (3 dof)")
    ax.set_title("consistency")
    for row in axes:
        for a in row:
            a.set_xlabel("time (s)")
            a.set_xlim(left=0)
            a.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    axes[1][1].legend(fontsize=8)
    fig.suptitle("line features in simulation (thesis §4.3.5): means over %d runs" % band[2])
    fig.tight_layout()
    fig.savefig(out_path, dpi=100)
    print("wrote %s" % out_path)


def draw_world(ax, world):
    for x1, y1, x2, y2 in world.get("wall", []):
        ax.plot([x1, x2], [y1, y2], color="black", linewidth=2, zorder=1)
    pts = np.array(world.get("point", []))
    ax.scatter(pts[:, 0], pts[:, 1], marker="x", color="black", s=25, zorder=2)


def estimated_segment(theta_true, p_true, theta_est, p_est, ends):
    """The estimated line over the extent of the true wall (ends projected)."""
    n = np.array([math.cos(theta_est), math.sin(theta_est)])
    return [e - (n.dot(e) - p_est) * n for e in ends]


def plot_maps(directory, variants, out_path):
    world = read_tagged(os.path.join(directory, "world.txt"))
    walls = [np.array(w).reshape(2, 2) for w in world.get("wall", [])]
    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    ax_path, ax_map = axes
    draw_world(ax_path, world)
    draw_world(ax_map, world)
    for i, name in enumerate(variants):
        color, label = STYLE.get(name, ("black", name))
        path = np.loadtxt(os.path.join(directory, name + "_path.txt"), ndmin=2)
        if i == 0:
            ax_path.plot(path[:, 1], path[:, 2], color="black", linestyle=":", linewidth=1,
                         label="true path")
        ax_path.plot(path[:, 3], path[:, 4], color=color, linewidth=1, label=label)
        m = read_tagged(os.path.join(directory, name + "_map.txt"))
        pts = np.array(m.get("point", []))
        ax_map.scatter(pts[:, 3], pts[:, 4], color=color, s=14, label=label, zorder=3)
        for row in m.get("line", []):
            w, theta_true, p_true, theta_est, p_est = row
            if math.isnan(p_est):
                continue
            seg = estimated_segment(theta_true, p_true, theta_est, p_est, walls[int(w)])
            ax_map.plot([seg[0][0], seg[1][0]], [seg[0][1], seg[1][1]], color=color,
                        linewidth=1, zorder=2)
    ax_path.set_title("paths of run 0 (Fig. 4.1)")
    ax_map.set_title("maps at the end of run 0 (Fig. 4.2)")
    for ax in axes:
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(out_path, dpi=100)
    print("wrote %s" % out_path)


def compare(runs, out_path):
    pairs = [("ptheta_lines", "points"), ("theta_lines", "points"),
             ("theta_lines", "ptheta_lines"), ("theta_lines_no_ends", "ptheta_lines"),
             ("theta_lines", "theta_lines_no_ends"), ("points_mecp_360", "points_360"),
             ("points_360", "points")]
    columns = ["mean_pos_err", "final_pos_err", "mean_point_err"]
    lines = ["# paired over seeds: mean of (a - b) ± its standard error (m); "
             "a better in k of n runs"]
    for a, b in pairs:
        if a not in runs or b not in runs:
            continue
        for c, column in enumerate(columns):
            diff = runs[a][:, c] - runs[b][:, c]
            n = len(diff)
            se = diff.std(ddof=1) / math.sqrt(n) if n > 1 else float("nan")
            lines.append("%s - %s %s: %+.4f ± %.4f, a better in %d of %d" % (
                a, b, column, diff.mean(), se, int((diff < 0).sum()), n))
    with open(out_path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines[1:]))
    print("wrote %s" % out_path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("directory")
    args = parser.parse_args()
    d = args.directory
    summary = read_summary(os.path.join(d, "summary.txt"))
    variants = [row["variant"] for row in summary]
    band = (float(summary[0]["band_lower"]), float(summary[0]["band_upper"]),
            int(summary[0]["runs"]))
    plot_errors(d, variants, band, os.path.join(d, "line_experiment.png"))
    plot_maps(d, variants, os.path.join(d, "line_experiment_map.png"))
    compare(read_runs(os.path.join(d, "runs.txt")), os.path.join(d, "comparison.txt"))


if __name__ == "__main__":
    main()
