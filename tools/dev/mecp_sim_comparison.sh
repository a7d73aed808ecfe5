#!/usr/bin/env bash
# MECP association against nearest neighbour and JCBB in the simulator
# with a rear laser (docs/results.md, "Rooms and MECP features in
# simulation"): the office loop of make demo, sim.launch rear_laser:=true
# (every front scan merged with the rear one into a 360-degree scan), once
# for each of
#   points / nn      nearest neighbour (the simulator's configuration)
#   points / jcbb    joint compatibility
#   points+mecp / nn MECP association over nearest neighbour
# each scored against the ground truth by tools/dev/sim_monitor.py. Prints
# a markdown table and writes it to OUT_DIR/table.md; each run's outputs
# are in OUT_DIR/<landmarks>-<method>/. Runs in real time: about 3 minutes
# a run.
#
# usage: tools/dev/mecp_sim_comparison.sh DEVEL_DIR [OUT_DIR]
#   DEVEL_DIR  a built workspace's devel folder (its setup.bash is sourced)
#   OUT_DIR    default output/mecp_sim_comparison
set -euo pipefail
export PATH=/usr/bin:/bin:$PATH
root=$(cd "$(dirname "$0")/../.." && pwd)
devel=${1:?usage: mecp_sim_comparison.sh DEVEL_DIR [OUT_DIR]}
out=$(mkdir -p "${2:-$root/output/mecp_sim_comparison}" && cd "${2:-$root/output/mecp_sim_comparison}" && pwd)
set +u
# shellcheck disable=SC1091
source "$devel/setup.bash"
set -u

field() {  # report line prefix -> the rest of that line
  sed -n "s/^$1: //p" "$2" | head -n 1
}

table=$out/table.md
{
  echo "| landmarks | association | final pose error | mean position error | average pose NEES | landmarks (duplicated) |"
  echo "|---|---|---|---|---|---|"
} > "$table"
port=11491
for combo in points/nn points/jcbb points+mecp/nn; do
  landmarks=${combo%/*} method=${combo#*/}
  dir=$out/${landmarks//+/_}-$method
  mkdir -p "$dir"
  sed -e "s/^pipeline:$/pipeline:\n  landmarks: $landmarks/" \
    -e "s/^  method: nn .*/  method: $method/" "$root/config/ekf_slam_sim.yaml" > "$dir/config.yaml"
  echo "== $landmarks, $method" >&2
  if "$root/tools/ci/run_sim_scored.sh" "$landmarks-$method" "$dir" office "$port" ekf_slam sim.launch \
    world:=office waypoints:=office_loop rear_laser:=true config:="$dir/config.yaml" \
    link_dir:=/tmp/ekf_slam_mecp_comparison_$$ >&2; then
    report=$dir/report.txt
    echo "| $landmarks | $method | $(field "final pose error" "$report" | cut -d'(' -f1) |" \
      "$(field "mean position error" "$report" | cut -d'(' -f1) |" \
      "$(field "average pose NEES" "$report" | cut -d'(' -f1) |" \
      "$(field landmarks "$report") |" >> "$table"
  else
    echo "| $landmarks | $method | run failed ($dir) | | | |" >> "$table"
  fi
  port=$((port + 1))
done
cat "$table"
