#!/usr/bin/python3
"""Draws one laser scan with its clusters, fitted lines and point features.

Input is the text written by the scan_features_dump tool (ekf_slam_ros):

    rosrun ekf_slam scan_features_dump ../shared/datasets/intel.orig.bag 1200 > scan.txt
    /usr/bin/python3 tools/analysis/plot_scan_features.py scan.txt output/scan_features.png

Everything is drawn in the laser frame (x forward, y left, metres): readings
coloured by cluster, lines in black, corners as red squares, segment ends
that are landmark candidates as green triangles, the other segment ends as
grey crosses (occluded, no return, scan boundary, unresolved), and 3-sigma
position ellipses around every landmark candidate.
"""
import argparse
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Ellipse  # noqa: E402


def read_dump(path):
    dump = {"points": [], "lines": [], "features": [], "header": None}
    with open(path) as f:
        for number, raw in enumerate(f, 1):
            fields = raw.split()
            if not fields:
                continue
            kind, values = fields[0], fields[1:]
            try:
                if kind == "scan":
                    dump["header"] = (int(values[0]), float(values[1]), int(values[2]), int(values[3]))
                elif kind == "point":
                    dump["points"].append((int(values[0]), float(values[1]), float(values[2]), int(values[3])))
                elif kind == "line":
                    dump["lines"].append([float(v) for v in values])
                elif kind == "feature":
                    dump["features"].append((values[0], values[1], values[2] == "1",
                                             *[float(v) for v in values[3:]]))
                else:
                    raise ValueError("unknown record '%s'" % kind)
            except (ValueError, IndexError) as error:
                sys.exit("%s:%d: cannot parse: %s (%s)" % (path, number, raw.strip(), error))
    if dump["header"] is None:
        sys.exit("%s: no 'scan' record; is it scan_features_dump output?" % path)
    return dump


def covariance_ellipse(x, y, var_x, cov_xy, var_y, sigmas, **style):
    trace_half = 0.5 * (var_x + var_y)
    root = math.sqrt(max(0.0, 0.25 * (var_x - var_y) ** 2 + cov_xy ** 2))
    major, minor = trace_half + root, max(0.0, trace_half - root)
    angle = 0.5 * math.degrees(math.atan2(2.0 * cov_xy, var_x - var_y))
    # Ellipse takes full widths (diameters).
    return Ellipse((x, y), 2 * sigmas * math.sqrt(major), 2 * sigmas * math.sqrt(minor),
                   angle=angle, fill=False, **style)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dump", help="scan_features_dump output")
    parser.add_argument("png", help="PNG to write")
    parser.add_argument("--title", default=None)
    args = parser.parse_args()
    dump = read_dump(args.dump)
    index, stamp, beams, valid = dump["header"]

    fig, ax = plt.subplots(figsize=(8, 8), dpi=110)
    cmap = plt.get_cmap("tab10")
    for beam, x, y, cluster in dump["points"]:
        ax.plot(x, y, ".", color=cmap(cluster % 10), markersize=3)
    for p, theta, x0, y0, x1, y1, *_ in dump["lines"]:
        ax.plot([x0, x1], [y0, y1], "-", color="black", linewidth=1.6)
    labels = set()

    def once(label):
        if label in labels:
            return None
        labels.add(label)
        return label

    for kind, context, landmark, x, y, vxx, vxy, vyy in dump["features"]:
        if kind == "corner":
            ax.plot(x, y, "s", color="red", markersize=7, label=once("corner"))
        elif landmark:
            ax.plot(x, y, "^", color="green", markersize=7, label=once("segment end (landmark)"))
        else:
            ax.plot(x, y, "x", color="grey", markersize=7, label=once("segment end (not a landmark)"))
        if landmark:
            ax.add_patch(covariance_ellipse(x, y, vxx, vxy, vyy, 3.0, color="blue", linewidth=0.8))
    ax.plot(0, 0, "k>", markersize=9, label="laser")
    ax.set_aspect("equal")
    ax.grid(True, linewidth=0.3)
    ax.set_xlabel("x (m, laser frame)")
    ax.set_ylabel("y (m)")
    corners = sum(1 for f in dump["features"] if f[0] == "corner")
    ax.set_title(args.title or "scan %d (t = %.2f s): %d/%d valid beams, %d lines, %d corners"
                 % (index, stamp, valid, beams, len(dump["lines"]), corners))
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(args.png)
    print("wrote %s" % args.png)


if __name__ == "__main__":
    main()
