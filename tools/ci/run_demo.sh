#!/usr/bin/env bash
# make demo: one loop of the office world through the whole system
# (sim.launch: simulator, the real drivers on pseudo-terminals, feature and
# SLAM nodes, the waypoint driver on the SLAM pose), scored against the
# simulator's ground truth by tools/dev/sim_monitor.py. Results in $1 (default
# output/): report.txt, demo.png, trajectory_{slam,odometry,true}.txt,
# landmarks.yaml. RVIZ=1 opens rviz on the run.
#
# It runs its own ROS master on a private port (run_sim_scored.sh). Expects
# the workspace's setup.bash to be sourced (the Makefile does).
set -euo pipefail
out=$(mkdir -p "${1:-output}" && cd "${1:-output}" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
rviz=$([ "${RVIZ:-0}" = "1" ] && echo true || echo false)
echo "run_demo: office world, one loop (a few minutes of simulated robot time in real time)"
"$here/run_sim_scored.sh" demo "$out" office "${DEMO_ROS_PORT:-11471}" ekf_slam sim.launch \
  world:=office waypoints:=office_loop rviz:=$rviz link_dir:=/tmp/ekf_slam_demo_$$
echo "run_demo: results in $out (report.txt, demo.png, trajectory_*.txt, landmarks.yaml)"
