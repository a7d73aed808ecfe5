#!/usr/bin/python3
"""Plots the output of ekf_slam_sim_demo: true, estimated and odometry paths,
true landmarks, and estimated landmarks with their 95% covariance ellipses.

usage: plot_demo.py DIR   (writes DIR/demo.png)
"""
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Ellipse  # noqa: E402

CHI2_2DOF_95 = 5.991464547107979  # 95% quantile of chi-square with 2 dof


def load(path):
    return np.atleast_2d(np.loadtxt(path, comments="#"))


def ellipse(x, y, cxx, cxy, cyy, **kw):
    """The 95% ellipse of a 2D Gaussian: full axes 2*sqrt(chi2 * eigenvalue)."""
    vals, vecs = np.linalg.eigh(np.array([[cxx, cxy], [cxy, cyy]]))
    vals = np.clip(vals, 0.0, None)
    angle = math.degrees(math.atan2(vecs[1, 1], vecs[0, 1]))
    width = 2.0 * math.sqrt(CHI2_2DOF_95 * vals[1])
    height = 2.0 * math.sqrt(CHI2_2DOF_95 * vals[0])
    return Ellipse((x, y), width, height, angle=angle, **kw)


def main(out_dir):
    truth = load(os.path.join(out_dir, "trajectory_true.txt"))
    est = load(os.path.join(out_dir, "trajectory_estimated.txt"))
    odo = load(os.path.join(out_dir, "trajectory_odometry.txt"))
    lm_true = load(os.path.join(out_dir, "landmarks_true.txt"))
    lm_est = load(os.path.join(out_dir, "landmarks_estimated.txt"))

    fig, ax = plt.subplots(figsize=(10, 7))
    ax.plot(odo[:, 1], odo[:, 2], color="tab:red", lw=1, label="odometry only")
    ax.plot(truth[:, 1], truth[:, 2], color="k", lw=1.5, ls="--", label="ground truth")
    ax.plot(est[:, 1], est[:, 2], color="tab:blue", lw=1.2, label="EKF-SLAM estimate")
    ax.scatter(lm_true[:, 0], lm_true[:, 1], marker="x", color="k", s=30, label="true landmarks")
    ax.scatter(lm_est[:, 1], lm_est[:, 2], marker="o", facecolors="none", edgecolors="tab:blue",
               s=20, label="estimated landmarks")
    for row in lm_est:
        # Ellipses are tiny next to the map; draw them magnified 10x, as stated.
        c = 100.0  # variance scale for a 10x axis magnification
        ax.add_patch(ellipse(row[1], row[2], c * row[3], c * row[4], c * row[5],
                             fill=False, color="tab:green", lw=0.8))
    ax.plot([], [], color="tab:green", label="95% covariance ellipses (x10)")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    report = open(os.path.join(out_dir, "report.txt")).read().splitlines()
    ax.set_title("\n".join(report[2:5]), fontsize=9)
    ax.legend(loc="center", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "demo.png"), dpi=110)
    print("wrote " + os.path.join(out_dir, "demo.png"))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
