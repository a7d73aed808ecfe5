#!/usr/bin/env bash
# make demo: runs the simulated EKF-SLAM demo into $1 (default output/) and
# plots it. Expects the workspace's setup.bash to be sourced (the Makefile
# does), so that `rosrun`-style lookup of the executable works without a roscore.
set -euo pipefail
out=${1:-output}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
demo=$(catkin_find --first-only --libexec ekf_slam ekf_slam_sim_demo 2>/dev/null || true)
[ -n "$demo" ] || { echo "run_demo: ekf_slam_sim_demo not built; run 'make build'" >&2; exit 1; }
"$demo" --out "$out"
/usr/bin/python3 "$root/tools/plot_demo.py" "$out"
echo "run_demo: results in $out (report.txt, demo.png, trajectory_*.txt, landmarks_*.txt)"
