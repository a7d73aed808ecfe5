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
# One office loop is worth about 2.4 independent pose-NEES samples: most of
# its error against the start lasts the loop. Measured as 6 / the variance
# of the loop's average NEES over 18 seeds (tools/dev/office_monte_carlo.sh,
# docs/results.md "The pose NEES"); the run alone would count more.
RUN_SAMPLES=${RUN_SAMPLES:-2.4} "$here/run_sim_scored.sh" demo "$out" office "${DEMO_ROS_PORT:-11471}" ekf_slam sim.launch \
  world:=office waypoints:=office_loop rviz:=$rviz link_dir:=/tmp/ekf_slam_demo_$$
echo "run_demo: results in $out (report.txt, demo.png, trajectory_*.txt, landmarks.yaml)"
