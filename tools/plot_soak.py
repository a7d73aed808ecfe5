#!/usr/bin/python3
"""Plots the soak runs: the filter soak (tools/filter_soak.cc) and the live
soak (tools/live_soak.py).

usage: tools/plot_soak.py --filter output/soak/filter_soak.txt \
                          --live output/soak/live_soak.txt --out docs/images/soak.png
Either input may be left out.
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--filter")
    parser.add_argument("--live")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    panels = [p for p in (args.filter, args.live) if p]
    if not panels:
        parser.error("give --filter, --live or both")
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 3.2 * len(panels)), squeeze=False)
    row = 0
    if args.filter:
        d = np.loadtxt(args.filter, ndmin=2)
        ax = axes[row][0]
        ax.plot(d[:, 0] / 1e3, d[:, 1] / 1024.0, color="tab:blue")
        ax.set_xlabel("filter iteration (thousands)")
        ax.set_ylabel("RSS (MiB)", color="tab:blue")
        ax.set_ylim(0, max(d[:, 1] / 1024.0) * 1.3)
        twin = ax.twinx()
        twin.plot(d[:, 0] / 1e3, d[:, 2], color="tab:orange")
        twin.set_ylabel("landmarks", color="tab:orange")
        twin.set_ylim(0, max(d[:, 2]) * 1.3)
        ax.set_title("filter on the landmark simulator: lowest eigenvalue of P %.2g"
                     % d[:, 3].min())
        row += 1
    if args.live:
        d = np.loadtxt(args.live, ndmin=2)
        ax = axes[row][0]
        ax.plot(d[:, 0] / 60.0, d[:, 1] / 1024.0, color="tab:blue")
        ax.set_xlabel("minutes")
        ax.set_ylabel("ekf_slam_node RSS (MiB)", color="tab:blue")
        ax.set_ylim(0, max(d[:, 1] / 1024.0) * 1.3)
        twin = ax.twinx()
        twin.plot(d[:, 0] / 60.0, d[:, 2], color="tab:green", alpha=0.5, linewidth=0.7)
        twin.set_ylabel("CPU (%)", color="tab:green")
        ax.set_title("live node, simulator driving the office loop")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print("wrote %s" % args.out)


if __name__ == "__main__":
    main()
