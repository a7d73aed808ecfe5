#!/usr/bin/env bash
# Fails when ekf_slam_core (the ROS-free maths library) includes a ROS header.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
hits=$(grep -rnE '#include *[<"](ros/|rosbag/|tf2|tf/|sensor_msgs|nav_msgs|geometry_msgs|visualization_msgs|std_msgs|diagnostic_)' \
  "$root/ekf_slam_core" || true)
if [ -n "$hits" ]; then
  echo "check_core_ros_free: ekf_slam_core must not include ROS headers:" >&2
  echo "$hits" >&2
  exit 1
fi
echo "check_core_ros_free: ekf_slam_core includes no ROS header"
