#!/usr/bin/python3
"""Plots the rooms experiment (tools/dev/rooms_experiment.cc), the
equivalent of the thesis's Figs. 4.7-4.8, and tabulates its
mis-associations.

usage: tools/analysis/plot_rooms_experiment.py DIR
Reads DIR/summary.txt, DIR/runs.txt, DIR/world.txt and per mode M
DIR/M.txt, DIR/M_path.txt, DIR/M_map.txt. Writes DIR/rooms_experiment.png
(run 0 of each nearest-neighbour mode: walls, true features, the map's landmarks with their
3-sigma ellipses, the estimated path and the features paired across a
wall),
DIR/rooms_mecp_partition.png (the polygons the MECP association remembered in
run 0, thesis Fig. 4.6), DIR/rooms_errors.png (position error, pose NEES and cross-wall matches over
time, means over the runs) and DIR/rooms_table.md (the summary as a
Markdown table, with paired differences between the modes; "loops
closed": runs whose return to room 1 paired at least 90 % of the
observations of mapped features with their first landmarks, and in brackets
that share over all runs).
"""
import argparse
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Ellipse  # noqa: E402

TITLE = {"open": "open association (every landmark)",
         "open_jcbb": "JCBB (every landmark)",
         "open_mecp": "MECP over open",
         "robot_room": "gated by the robot's room",
         "observation_room": "gated by the observation's room",
         "observation_room_mecp": "MECP over the observation's room"}
COLOR = {"open": "tab:red", "open_jcbb": "tab:green", "open_mecp": "tab:purple",
         "robot_room": "tab:orange", "observation_room": "tab:blue",
         "observation_room_mecp": "tab:cyan"}
# The maps drawn: the nearest-neighbour modes (the others' maps look alike).
MAP_MODES = ["open", "robot_room", "observation_room"]


def read_table(path):
    header, rows = None, []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                header = line[1:].split()
            elif line.strip():
                rows.append(dict(zip(header, line.split())))
    return rows


def read_tagged(path):
    out = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            tag, *values = line.split()
            out.setdefault(tag, []).append([float(v) for v in values])
    return out


def draw_world(ax, world):
    for x1, y1, x2, y2 in world.get("wall", []):
        ax.plot([x1, x2], [y1, y2], color="0.4", linewidth=2.5, zorder=1)
    for x1, y1, x2, y2 in world.get("door", []):
        ax.plot([x1, x2], [y1, y2], color="tab:green", linewidth=1, linestyle=":", zorder=1)
    pts = np.array(world["point"])
    ax.scatter(pts[:, 0], pts[:, 1], marker="x", color="black", s=14, linewidths=0.8,
               zorder=2, label="true features")


def plot_maps(directory, modes, out_path):
    world = read_tagged(os.path.join(directory, "world.txt"))
    features = np.array(world["point"])
    fig, axes = plt.subplots(len(modes), 1, figsize=(11, 4.0 * len(modes)))
    for ax, mode in zip(np.atleast_1d(axes), modes):
        draw_world(ax, world)
        path = np.loadtxt(os.path.join(directory, mode + "_path.txt"), ndmin=2)
        ax.plot(path[:, 1], path[:, 2], color="black", linestyle=":", linewidth=0.8,
                label="true path")
        ax.plot(path[:, 3], path[:, 4], color="tab:gray", linewidth=0.8, label="estimated path")
        m = read_tagged(os.path.join(directory, mode + "_map.txt"))
        lms = np.array(m.get("landmark", []))
        for _id, _f, x, y, cxx, cxy, cyy in lms:
            values, vectors = np.linalg.eigh(np.array([[cxx, cxy], [cxy, cyy]]))
            angle = math.degrees(math.atan2(vectors[1, 1], vectors[0, 1]))
            ax.add_patch(Ellipse((x, y), 6 * math.sqrt(max(values[1], 0)),
                                 6 * math.sqrt(max(values[0], 0)), angle=angle,
                                 fill=False, color="tab:blue", linewidth=0.7, zorder=3))
        ax.scatter(lms[:, 2], lms[:, 3], marker="+", color="tab:red", s=30, zorder=4,
                   label="landmarks (3σ ellipses)")
        # The features paired across a wall lie centimetres apart: ringed,
        # so that they show at this scale.
        crosses = m.get("cross", [])
        paired = sorted({int(f) for row in crosses for f in row[1:3]})
        if paired:
            ax.scatter(features[paired, 0], features[paired, 1], s=160, facecolors="none",
                       edgecolors="magenta", linewidths=1.5, zorder=5,
                       label="paired across a wall")
        ax.set_title("%s, run 0: %d cross-wall matches, %d landmarks" % (
            TITLE.get(mode, mode), len(crosses), len(lms)))
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(out_path, dpi=100, bbox_inches="tight")  # the legends sit outside the axes
    print("wrote %s" % out_path)


def plot_partition(directory, mode, out_path):
    """The remembered MECPs of run 0 over the world: thesis Fig. 4.6."""
    world = read_tagged(os.path.join(directory, "world.txt"))
    polygons = read_tagged(os.path.join(directory, mode + "_map.txt")).get("polygon", [])
    fig, ax = plt.subplots(figsize=(11, 4.2))
    draw_world(ax, world)
    colours = plt.get_cmap("tab20")
    for i, flat in enumerate(polygons):
        xy = np.array(flat).reshape(-1, 2)
        closed = np.vstack([xy, xy[:1]])
        ax.fill(xy[:, 0], xy[:, 1], color=colours(i % 20), alpha=0.08, zorder=0)
        ax.plot(closed[:, 0], closed[:, 1], color=colours(i % 20), linewidth=0.8, zorder=2)
    ax.set_title("%s, run 0: the %d polygons remembered (each its members' estimates)"
                 % (TITLE.get(mode, mode), len(polygons)))
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    fig.tight_layout()
    fig.savefig(out_path, dpi=100)
    print("wrote %s" % out_path)


def plot_errors(directory, modes, summary, out_path):
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for mode in modes:
        d = np.loadtxt(os.path.join(directory, mode + ".txt"), ndmin=2)
        label = TITLE.get(mode, mode)
        axes[0].plot(d[:, 1], d[:, 2], color=COLOR.get(mode), label=label, linewidth=1)
        axes[1].plot(d[:, 1], d[:, 3], color=COLOR.get(mode), label=label, linewidth=0.8)
        axes[2].plot(d[:, 1], d[:, 4], color=COLOR.get(mode), label=label, linewidth=1)
    lower, upper = float(summary[0]["band_lower"]), float(summary[0]["band_upper"])
    axes[1].axhline(lower, color="black", linestyle="--", linewidth=0.8)
    axes[1].axhline(upper, color="black", linestyle="--", linewidth=0.8, label="95 % band")
    axes[1].set_yscale("log")
    axes[0].set_ylabel("position error (m)")
    axes[1].set_ylabel("average pose NEES (3 dof)")
    axes[2].set_ylabel("cross-wall matches so far (per run)")
    for ax in axes:
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("rooms world (thesis §4.4.5): means over %s runs" % summary[0]["runs"])
    fig.tight_layout()
    fig.savefig(out_path, dpi=100)
    print("wrote %s" % out_path)


def paired(runs, mode, column):
    by_mode = {}
    for row in runs:
        by_mode.setdefault(row["mode"], {})[row["seed"]] = float(row[column])
    if "open" not in by_mode or mode not in by_mode:
        return None
    seeds = sorted(set(by_mode["open"]) & set(by_mode[mode]))
    diff = np.array([by_mode[mode][s] - by_mode["open"][s] for s in seeds])
    se = diff.std(ddof=1) / math.sqrt(len(diff)) if len(diff) > 1 else float("nan")
    return diff.mean(), se, int((diff < 0).sum()), len(diff)


def write_table(summary, runs, out_path):
    lines = ["| association | runs | matches / run | mis-associations / run | "
             "cross-wall / run (total; in a doorway; runs with any) | "
             "landmarks / run (duplicates) | "
             "mean / final position error (m) | average pose NEES | loops closed |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in summary:
        lines.append("| %s | %s | %.0f | %s | %s (%s; %s; %s) | %s (%s) | %s / %s | %s | %s |" % (
            TITLE.get(row["mode"], row["mode"]), row["runs"], float(row["matches_per_run"]),
            row["mis_per_run"], row["cross_wall_per_run"], row["cross_wall_total"],
            row["cross_wall_at_door_total"], row["runs_with_cross_wall"], row["landmarks_per_run"], row["duplicates_per_run"],
            row["mean_pos_err_m"], row["final_pos_err_m"], row["average_nees"],
            "%s (%.0f %%)" % (row["loops_closed"], 100 * float(row["return_right_fraction"]))))
    for row in summary:
        mode = row["mode"]
        if mode == "open":
            continue
        lines.append("")
        lines.append("Paired over seeds, %s minus open: mean ± standard error "
                     "(gated lower in k of n runs)" % TITLE.get(mode, mode))
        lines.append("")
        for column in ["cross_wall", "mis_associations", "duplicates", "mean_pos_err_m",
                       "final_pos_err_m"]:
            result = paired(runs, mode, column)
            if result:
                lines.append("- %s: %+.4f ± %.4f (%d of %d)" % ((column,) + result))
    with open(out_path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    print("wrote %s" % out_path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("directory")
    args = parser.parse_args()
    d = args.directory
    summary = read_table(os.path.join(d, "summary.txt"))
    modes = [row["mode"] for row in summary]
    plot_maps(d, [m for m in MAP_MODES if m in modes], os.path.join(d, "rooms_experiment.png"))
    plot_errors(d, modes, summary, os.path.join(d, "rooms_errors.png"))
    if "open_mecp" in modes:
        plot_partition(d, "open_mecp", os.path.join(d, "rooms_mecp_partition.png"))
    write_table(summary, read_table(os.path.join(d, "runs.txt")),
                os.path.join(d, "rooms_table.md"))


if __name__ == "__main__":
    main()
