#!/usr/bin/env bash
# rviz (config/rviz/robot.rviz) on a replay of a bag through the live nodes,
# photographed at fractions of the log: the views of docs/live_system.md.
#   tools/dev/replay_screenshots.sh BAG OUT_PREFIX [RATE [FRACTION ...]]
# writes OUT_PREFIX_<percent>pct.png for each fraction (default 0.5 and 1.0)
# of the log's duration, at RATE times real time (default 10). For a
# fraction below 1 the player is paused while rviz renders. Needs the
# workspace sourced; runs its own ROS master on port 11391.
#   tools/dev/replay_screenshots.sh ../shared/datasets/aces.orig.bag docs/images/rviz_replay_aces
set -eu
bag=$(realpath "$1")
prefix=$2
rate=${3:-10}
shift $(( $# < 3 ? $# : 3 ))
fractions=("$@")
[ ${#fractions[@]} -eq 0 ] && fractions=(0.5 1.0)
here=$(cd "$(dirname "$0")" && pwd)
config=$(cd "$here/../../config/rviz" && pwd)/robot.rviz

mkdir -p "$(dirname "$prefix")"
export ROS_MASTER_URI=http://localhost:11391
info=$(rosbag info --yaml "$bag")
start=$(printf '%s\n' "$info" | sed -n 's/^start: //p')
end=$(printf '%s\n' "$info" | sed -n 's/^end: //p')

roslaunch -p 11391 ekf_slam offline.launch bag:="$bag" replay:=true rate:="$rate" \
  stop_at_end:=false > "$prefix.replay.log" 2>&1 &
launch=$!
trap 'kill -INT $launch 2>/dev/null; wait $launch 2>/dev/null' EXIT

for fraction in "${fractions[@]}"; do
  percent=$(/usr/bin/python3 -c "print(round(100 * $fraction))")
  if /usr/bin/python3 -c "import sys; sys.exit(0 if $fraction < 1 else 1)"; then
    at=$(/usr/bin/python3 -c "print($start + $fraction * ($end - $start))")
    pause=(--pause-service /bag_player/pause_playback)
  else
    # The end: the player stops there and SLAM keeps the finished map.
    at=$(/usr/bin/python3 -c "print($end - 0.5)")
    pause=()
  fi
  /usr/bin/python3 "$here/rviz_screenshot.py" --config "$config" --out "${prefix}_${percent}pct.png" \
    --at-clock "$at" "${pause[@]}" --wait 15
done
