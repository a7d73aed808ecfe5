#!/usr/bin/python3
"""Figures of an ekf_slam_offline run, in the manner of the thesis's Chapter 5.

usage: plot_offline.py DIR

Reads DIR/map*.pgm + .yaml, DIR/trajectory_*.txt, DIR/landmarks.yaml and
DIR/first_last_scans.txt; writes
  DIR/fig_map_slam_vs_odometry.png   the grid and path from SLAM vs from odometry
  DIR/fig_first_last_scans.png       first and last scan in each frame (Fig. 5.7)
  DIR/fig_smoothing.png              the grid before and after smoothing (Fig. 5.11)
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402
from ekf_slam_tools.worlds import read_pgm  # noqa: E402

# libyaml's loader where PyYAML has it: a tenth of the pure-Python one's time.
YamlLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def show_map(ax, out_dir, base, title, traj, margin=5.0):
    """The map image around traj's extent (crop_to's view), axes cropped to it."""
    meta = yaml.load(open(os.path.join(out_dir, base + ".yaml")), Loader=YamlLoader)
    image = read_pgm(os.path.join(out_dir, meta["image"]))
    res = float(meta["resolution"])
    x0, y0 = meta["origin"][0], meta["origin"][1]
    h, w = image.shape
    # Only the part in view goes to imshow, whole pixels on the map's
    # lattice: the same picture, without resampling the rest of a large map.
    lo_x, hi_x, lo_y, hi_y = crop_to(ax, traj, margin)
    c0 = min(max(int((lo_x - x0) / res) - 1, 0), w)
    c1 = min(max(int((hi_x - x0) / res) + 2, c0), w)
    r0 = min(max(int((lo_y - y0) / res) - 1, 0), h)
    r1 = min(max(int((hi_y - y0) / res) + 2, r0), h)
    # Image rows run from the top (largest y) down.
    view = image[h - r1:h - r0, c0:c1]
    if view.size:
        ax.imshow(view, cmap="gray", vmin=0, vmax=255, origin="upper",
                  extent=[x0 + c0 * res, x0 + c1 * res, y0 + r0 * res, y0 + r1 * res])
    crop_to(ax, traj, margin)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def trajectory(out_dir, name):
    return np.atleast_2d(np.loadtxt(os.path.join(out_dir, "trajectory_%s.txt" % name)))


def in_frame_of(traj, first_pose):
    """traj (stamp x y theta rows) moved rigidly so that its first pose is first_pose."""
    d_theta = first_pose[3] - traj[0, 3]
    c, s = np.cos(d_theta), np.sin(d_theta)
    out = traj.copy()
    dx, dy = traj[:, 1] - traj[0, 1], traj[:, 2] - traj[0, 2]
    out[:, 1] = first_pose[1] + c * dx - s * dy
    out[:, 2] = first_pose[2] + s * dx + c * dy
    out[:, 3] = traj[:, 3] + d_theta
    return out


def crop_to(ax, traj, margin=5.0):
    """Limits the view to traj's extent plus margin; returns the limits."""
    lo_x, hi_x = traj[:, 1].min() - margin, traj[:, 1].max() + margin
    lo_y, hi_y = traj[:, 2].min() - margin, traj[:, 2].max() + margin
    ax.set_xlim(lo_x, hi_x)
    ax.set_ylim(lo_y, hi_y)
    return lo_x, hi_x, lo_y, hi_y


def save(fig, out_dir, name):
    """Writes fig as a PNG and closes it. Fixed margins in place of
    tight_layout, and light PNG compression: a tenth of the figures' time."""
    fig.subplots_adjust(left=0.06, right=0.98, bottom=0.08, top=0.95, wspace=0.2)
    fig.savefig(os.path.join(out_dir, name), dpi=100, pil_kwargs={"compress_level": 1})
    plt.close(fig)


def main(out_dir):
    smoothed = trajectory(out_dir, "smoothed")
    filtered = trajectory(out_dir, "filtered")
    odometry = trajectory(out_dir, "odometry")

    fig, axes = plt.subplots(1, 2, figsize=(14, 7))
    show_map(axes[0], out_dir, "map", "EKF-SLAM (smoothed) map and path", smoothed)
    axes[0].plot(smoothed[:, 1], smoothed[:, 2], color="tab:blue", lw=0.6, label="smoothed path")
    # The scan-matching front end's own track (the filter's control), when it ran.
    if os.path.exists(os.path.join(out_dir, "trajectory_scan_matched.txt")):
        # It lives in the odometry frame: place its first pose on the smoothed one.
        matched = in_frame_of(trajectory(out_dir, "scan_matched"), smoothed[0])
        axes[0].plot(matched[:, 1], matched[:, 2], color="tab:green", lw=0.5, ls="--",
                     label="scan-matched control")
    landmarks = yaml.load(open(os.path.join(out_dir, "landmarks.yaml")),
                          Loader=YamlLoader)["landmarks"] or []
    if landmarks:
        axes[0].scatter([l["x"] for l in landmarks], [l["y"] for l in landmarks], s=4,
                        color="tab:red", label="landmarks")
    axes[0].legend(loc="upper right", fontsize=8)
    crop_to(axes[0], smoothed)
    show_map(axes[1], out_dir, "map_odometry", "odometry only", odometry)
    axes[1].plot(odometry[:, 1], odometry[:, 2], color="tab:red", lw=0.6)
    crop_to(axes[1], odometry)
    save(fig, out_dir, "fig_map_slam_vs_odometry.png")

    rows = [line.split() for line in open(os.path.join(out_dir, "first_last_scans.txt"))
            if not line.startswith("#")]
    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    for ax, frame in zip(axes, ["odometry", "slam"]):
        for which, color in [("first", "tab:blue"), ("last", "tab:red")]:
            pts = np.array([[float(r[2]), float(r[3])] for r in rows
                            if r[0] == frame and r[1] == which] or np.zeros((0, 2)))
            if len(pts):
                ax.scatter(pts[:, 0], pts[:, 1], s=2, color=color, label="%s scan" % which)
        ax.set_title("first and last scan placed with %s poses" % frame, fontsize=10)
        ax.set_aspect("equal")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    save(fig, out_dir, "fig_first_last_scans.png")

    fig, axes = plt.subplots(1, 2, figsize=(14, 7))
    show_map(axes[0], out_dir, "map_filtered", "grid from the filtered poses", filtered)
    show_map(axes[1], out_dir, "map", "grid from the smoothed poses", smoothed)
    save(fig, out_dir, "fig_smoothing.png")
    print("figures written to " + out_dir)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
