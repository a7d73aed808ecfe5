#!/usr/bin/env bash
# Localisation in a saved map, scored against the simulator's ground truth:
# one loop of the office world driven by the waypoint driver on the pose
# that launch/localization.launch gives (mapping off, the saved landmarks
# as the filter's map, the start at the map's origin with amcl's default
# uncertainty). MAP is a landmark file saved by ~save_map on the office
# world from the robot's start pose: `make demo` writes one
# (output/landmarks.yaml). Results in OUT: report.txt, trajectory_*.txt.
#   tools/dev/localization_check.sh MAP OUT
# Expects the workspace's setup.bash to be sourced.
set -euo pipefail
map=$(cd "$(dirname "${1:?usage: localization_check.sh MAP OUT}")" && pwd)/$(basename "$1")
out=$(mkdir -p "${2:?usage: localization_check.sh MAP OUT}" && cd "$2" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
launch=$out/localization_check.launch
# The simulation's own SLAM configuration: the one the map was made with.
cat > "$launch" <<LAUNCH
<launch>
  <include file="\$(find ekf_slam)/launch/sim.launch">
    <arg name="slam" value="false"/>
    <arg name="waypoints" value="office_loop"/>
    <arg name="link_dir" value="/tmp/ekf_slam_localization_$$"/>
  </include>
  <include file="\$(find ekf_slam)/launch/localization.launch">
    <arg name="map" value="$map"/>
    <arg name="config" value="\$(find ekf_slam)/config/ekf_slam_sim.yaml"/>
  </include>
</launch>
LAUNCH
echo "localization_check: office world, one loop localising in $map"
"$root/tools/ci/run_sim_scored.sh" localization "$out" office "${LOCALIZATION_ROS_PORT:-11473}" \
  "$launch"
cat "$out/report.txt"
