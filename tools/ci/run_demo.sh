#!/usr/bin/env bash
# make demo: one loop of the office world through the whole system
# (sim.launch: simulator, the real drivers on pseudo-terminals, feature and
# SLAM nodes, the waypoint driver on the SLAM pose), scored against the
# simulator's ground truth by tools/dev/sim_monitor.py. Results in $1 (default
# output/): report.txt, demo.png, trajectory_{slam,odometry,true}.txt,
# landmarks.yaml. RVIZ=1 opens rviz on the run.
#
# It runs its own ROS master on a private port, so it neither needs nor
# disturbs a roscore you may have running. Expects the workspace's
# setup.bash to be sourced (the Makefile does).
set -euo pipefail
out=$(mkdir -p "${1:-output}" && cd "${1:-output}" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
rviz=$([ "${RVIZ:-0}" = "1" ] && echo true || echo false)
port=${DEMO_ROS_PORT:-11471}
export ROS_MASTER_URI=http://localhost:$port
export ROS_HOME=${ROS_HOME:-$out/ros_home}
log=$out/demo_launch.log
rm -f "$out/report.txt"

echo "run_demo: office world, one loop (a few minutes of simulated robot time in real time)"
roslaunch -p "$port" ekf_slam sim.launch world:=office waypoints:=office_loop rviz:=$rviz \
  link_dir:=/tmp/ekf_slam_demo_$$ > "$log" 2>&1 &
launch_pid=$!
cleanup() { kill -INT "$launch_pid" 2>/dev/null || true; wait "$launch_pid" 2>/dev/null || true; }
trap cleanup EXIT
status=0
/usr/bin/python3 "$root/tools/dev/sim_monitor.py" --out "$out" --world office --timeout 900 || status=$?
if [ $status -ne 0 ]; then
  echo "run_demo: the run did not complete; the launch log is $log" >&2
  tail -n 30 "$log" >&2
  exit $status
fi
echo "run_demo: results in $out (report.txt, demo.png, trajectory_*.txt, landmarks.yaml)"
