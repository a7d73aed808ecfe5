#!/usr/bin/env bash
# The thesis's EKF-SLAM and what each stage of the shipped system adds to
# it (docs/results.md, "The thesis's system, stage by stage"). Every real log
# in ../shared/datasets runs through ekf_slam_offline
# (tools/ci/run_dataset_benchmark.sh) once per stage:
#   thesis   config/ekf_slam_thesis.yaml (--preset thesis): the robot's
#            odometry as the control, corners and θ-only wall lines, nearest
#            neighbour, no back end, the RTS smoother
#   +scan    the laser scan matcher's pose as the control
#   +loops   the loop-closing back end (the EKF re-anchored after each loop)
#   +full    the full smoother in place of RTS
#   default  the built-in defaults (corners alone as landmarks)
# and prints OUT_DIR/table.md: per stage and log, the relation error of the
# pose published live (trajectory_live.txt) and of the smoothed trajectory
# (trajectory_smoothed.txt: RTS or the full smoother, per the stage).
# With SIM=1 it also drives the office and carton worlds once with the
# simulation's configuration and once with preset:=thesis
# (tools/ci/run_sim_scored.sh; about 3 min each) into OUT_DIR/sim_*.
#
# usage: [SIM=1] tools/dev/stage_comparison.sh DEVEL_DIR [OUT_DIR]
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
root=$(cd "$(dirname "$0")/../.." && pwd)
devel=${1:?usage: stage_comparison.sh DEVEL_DIR [OUT_DIR]}
out=$(mkdir -p "${2:-$root/output/stage_comparison}" && cd "${2:-$root/output/stage_comparison}" && pwd)
thesis=$root/config/ekf_slam_thesis.yaml

# stage name -> its configuration file (the thesis preset, then what changes)
stage_config() {
  local file=$out/$1.yaml
  case $1 in
    thesis) cp "$thesis" "$file" ;;
    scan) sed -e '/^scan_matching:/,/^$/s/enabled: false/enabled: true/' "$thesis" > "$file" ;;
    loops) sed -e 's/enabled: false/enabled: true/' "$thesis" > "$file" ;;
    full) sed -e 's/enabled: false/enabled: true/' -e 's/method: rts/method: full/' "$thesis" > "$file" ;;
    default) : > "$file" ;;
  esac
  echo "$file"
}

stages="thesis scan loops full default"
for stage in $stages; do
  echo "== stage $stage"
  CONFIG=$(stage_config "$stage") "$root/tools/ci/run_dataset_benchmark.sh" "$devel" \
    "$out/$stage" > "$out/$stage.log" 2>&1
done

logs=$(sed -n '3,$s/^| \([a-z-]*\) | .*/\1/p' "$out/thesis/summary.md")
{
  printf '| stage |'
  for log in $logs; do printf ' %s live [m] | %s smoothed [m] |' "$log" "$log"; done
  printf '\n|---|'
  for _ in $logs; do printf -- '---|---|'; done
  printf '\n'
  for stage in $stages; do
    printf '| %s |' "$stage"
    for log in $logs; do
      # summary.md: | log | raw | causal (live) | final (smoothed) | graph | wall | memory |
      awk -F'|' -v name="$log" '$2 == " " name " " { printf " %s | %s |", $4, $5 }' \
        "$out/$stage/summary.md" | sed 's/  */ /g'
    done
    printf '\n'
  done
} > "$out/table.md"
cat "$out/table.md"

if [ "${SIM:-0}" = "1" ]; then
  set +u
  # shellcheck disable=SC1091
  source "$devel/setup.bash"
  set -u
  for world in office:office_loop carton_layout:carton_loop; do
    name=${world%%:*} loop=${world##*:}
    for preset in none thesis; do
      dir=$out/sim_${name}_$preset
      mkdir -p "$dir"
      echo "== $name, preset $preset"
      "$root/tools/ci/run_sim_scored.sh" stage "$dir" "$name" "${STAGE_ROS_PORT:-11475}" \
        ekf_slam sim.launch world:="$name" waypoints:="$loop" preset:="$preset" \
        link_dir:=/tmp/ekf_slam_stage_$$ || echo "stage_comparison: $dir did not complete" >&2
      grep -i "error\|nees" "$dir/report.txt" 2>/dev/null | head -5 || true
    done
  done
fi
