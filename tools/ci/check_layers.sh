#!/usr/bin/env bash
# Fails when an include runs up the layers of docs/architecture.md ("Folders"):
#   ekf_slam_ros/                                   the ROS adapters (top)
#   p3dx_driver/, sick_lms200_driver/               the drivers
#   ros_params/, ros_conversions/, serial_io/       what the drivers build on
#   ekf_slam_core/                                  the maths, no ROS (bottom)
# Nothing below ekf_slam_ros/ includes from it, and the core includes only
# itself (its ROS-free rule is tools/ci/check_core_ros_free.sh).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
status=0
check() {  # check <what may not be included, as an ERE> <folder>...
  local pattern=$1
  shift
  local hits
  hits=$(grep -rnE "^[[:space:]]*#[[:space:]]*include[[:space:]]*[<\"]($pattern)/" "$@" || true)
  if [ -n "$hits" ]; then
    echo "check_layers: $* must not include $pattern/ (a layer above):" >&2
    echo "$hits" >&2
    status=1
  fi
}
check 'ekf_slam_ros' p3dx_driver sick_lms200_driver serial_io ros_params ros_conversions
check 'ekf_slam_ros|p3dx_driver|sick_lms200_driver|serial_io|ros_params|ros_conversions' ekf_slam_core
[ $status -eq 0 ] && echo "check_layers: no include runs up a layer"
exit $status
