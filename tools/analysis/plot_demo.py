#!/usr/bin/python3
"""Plots the output of ekf_slam_sim_demo: true, estimated and odometry paths,
true landmarks, and estimated landmarks with their 95% covariance ellipses
(DIR/demo.png); and the loop closing as the thesis draws it in its Fig. 5.2
(DIR/loop_closing.png): the map just before and just after the step in which
the robot's position variance falls the most, features as red crosses with
blue 95 % ellipses, the robot as a green circle with its own ellipse.

usage: plot_demo.py DIR
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


def loop_closing(out_dir):
    """Two panels: the filter one step before and one step after the loop
    closing, at the true scale of the ellipses."""
    truth = load(os.path.join(out_dir, "trajectory_true.txt"))
    est = load(os.path.join(out_dir, "trajectory_estimated.txt"))
    lm_true = load(os.path.join(out_dir, "landmarks_true.txt"))
    fig, axes = plt.subplots(1, 2, figsize=(13, 6.2), sharex=True, sharey=True)
    for ax, when in zip(axes, ("before", "after")):
        robot = load(os.path.join(out_dir, "robot_%s_closing.txt" % when))[0]
        lm = load(os.path.join(out_dir, "landmarks_%s_closing.txt" % when))
        stamp = robot[0]
        ax.plot(truth[truth[:, 0] <= stamp, 1], truth[truth[:, 0] <= stamp, 2], color="k",
                lw=1, ls="--", label="true path")
        ax.plot(est[est[:, 0] < stamp, 1], est[est[:, 0] < stamp, 2], color="tab:blue", lw=1,
                label="estimated path")
        ax.scatter(lm_true[:, 0], lm_true[:, 1], marker=".", color="0.6", s=12,
                   label="true landmarks")
        ax.scatter(lm[:, 1], lm[:, 2], marker="+", color="tab:red", s=40, label="features")
        for row in lm:
            ax.add_patch(ellipse(row[1], row[2], row[3], row[4], row[5], fill=False,
                                 color="tab:blue", lw=0.8))
        ax.add_patch(ellipse(robot[1], robot[2], robot[4], robot[5], robot[6], fill=False,
                             color="tab:blue", lw=1.2))
        ax.add_patch(plt.Circle((robot[1], robot[2]), 0.25, color="tab:green", fill=True))
        variance = robot[4] + robot[6]
        ax.set_title("%s the loop closing (t = %.1f s): robot position variance %.3f m²" %
                     (when, stamp, variance), fontsize=10)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("y [m]")
    axes[0].plot([], [], color="tab:blue", lw=0.8, label="95 % ellipses")
    axes[0].legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "loop_closing.png"), dpi=90)
    print("wrote " + os.path.join(out_dir, "loop_closing.png"))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
    loop_closing(sys.argv[1])
