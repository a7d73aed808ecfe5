#!/usr/bin/python3
"""Plots the soak runs: the filter soak (tools/dev/filter_soak.cc) and the live
soak (tools/dev/live_soak.py).

usage: tools/analysis/plot_soak.py --filter output/soak/filter_soak.txt \
                          --live output/soak/live_soak.txt \
                          --replay output/soak_intel/live_soak.txt --out docs/images/soak.png
Any input may be left out. --replay is a live soak of a recorded log
(live_soak.py --bag), drawn with its key scans.
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_pair(ax, x, rss_kib, other, other_label, other_color, title):
    """RSS (MiB) on the left axis and another series on the right one."""
    ax.plot(x, rss_kib / 1024.0, color="tab:blue")
    ax.set_ylim(0, max(rss_kib / 1024.0) * 1.3)
    twin = ax.twinx()
    twin.plot(x, other, color=other_color, linewidth=0.8)
    twin.set_ylabel(other_label, color=other_color)
    ax.set_title(title)
    return twin


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--filter")
    parser.add_argument("--live")
    parser.add_argument("--replay")
    parser.add_argument("--replay-title", default="live node, Intel log replayed at 1x, "
                        "shipped configuration (loop closure on)")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    panels = [p for p in (args.filter, args.live, args.replay) if p]
    if not panels:
        parser.error("give --filter, --live, --replay or several")
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 3.2 * len(panels)), squeeze=False)
    row = 0
    if args.filter:
        d = np.loadtxt(args.filter, ndmin=2)
        ax = axes[row][0]
        twin = plot_pair(ax, d[:, 0] / 1e3, d[:, 1], d[:, 2], "landmarks", "tab:orange",
                         "filter on the landmark simulator: lowest eigenvalue of P %.2g"
                         % d[:, 3].min())
        twin.set_ylim(0, max(d[:, 2]) * 1.3)
        ax.set_xlabel("filter iteration (thousands)")
        ax.set_ylabel("RSS (MiB)", color="tab:blue")
        row += 1
    if args.live:
        d = np.loadtxt(args.live, ndmin=2)
        ax = axes[row][0]
        plot_pair(ax, d[:, 0] / 60.0, d[:, 1], d[:, 2], "CPU (%)", "tab:green",
                  "live node, simulator driving the office loop")
        ax.set_xlabel("minutes")
        ax.set_ylabel("ekf_slam_node RSS (MiB)", color="tab:blue")
        row += 1
    if args.replay:
        d = np.loadtxt(args.replay, ndmin=2)
        ax = axes[row][0]
        twin = plot_pair(ax, d[:, 0] / 60.0, d[:, 1], d[:, 5], "key scans", "tab:orange",
                         args.replay_title)
        twin.plot(d[:, 0] / 60.0, d[:, 5] - d[:, 6], color="tab:red", linewidth=0.8)
        twin.set_ylabel("key scans (red: holding readings)", color="tab:orange")
        ax.set_xlabel("minutes")
        ax.set_ylabel("ekf_slam_node RSS (MiB)", color="tab:blue")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print("wrote %s" % args.out)


if __name__ == "__main__":
    main()
