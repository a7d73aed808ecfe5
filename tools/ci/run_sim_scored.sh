#!/usr/bin/env bash
# One simulated run scored against the simulator's ground truth
# (tools/dev/sim_monitor.py), on a private ROS master so that it neither
# needs nor disturbs a roscore you may have running: roslaunch with the
# given arguments in the background, the monitor until the waypoint loop
# ends, then the launch stopped. Serves make demo (run_demo.sh),
# tools/dev/localization_check.sh and tools/dev/stage_comparison.sh.
#
#   run_sim_scored.sh NAME OUT WORLD PORT ROSLAUNCH_ARGS...
#
# NAME prefixes the messages and names the launch log (OUT/NAME_launch.log);
# the monitor writes report.txt, trajectory_*.txt and the rest into OUT.
# RUN_SAMPLES (optional): what one run of this loop is worth in independent
# samples, for the NEES band (sim_monitor.py --run-samples).
# Exit status: the monitor's. Expects the workspace's setup.bash sourced.
set -euo pipefail
name=$1 out=$2 world=$3 port=$4
shift 4
root=$(cd "$(dirname "$0")/../.." && pwd)
export ROS_MASTER_URI=http://localhost:$port
export ROS_HOME=${ROS_HOME:-$out/ros_home}
log=$out/${name}_launch.log
rm -f "$out/report.txt"
roslaunch -p "$port" "$@" > "$log" 2>&1 &
launch_pid=$!
cleanup() { kill -INT "$launch_pid" 2>/dev/null || true; wait "$launch_pid" 2>/dev/null || true; }
trap cleanup EXIT
status=0
/usr/bin/python3 "$root/tools/dev/sim_monitor.py" --out "$out" --world "$world" --timeout 900 \
  ${RUN_SAMPLES:+--run-samples "$RUN_SAMPLES"} || status=$?
if [ $status -ne 0 ]; then
  echo "$name: the run did not complete; the launch log is $log" >&2
  tail -n 30 "$log" >&2
fi
exit $status
