#!/usr/bin/env bash
# The landmark kinds and the two association methods on the real logs
# (docs/results.md, "Line landmarks on the real logs"): every log in
# ../shared/datasets, run by ekf_slam_offline with every other value the
# built-in default, once for each combination of
#   pipeline.landmarks      points | points+lines | points+lines_theta
#   association.method      nn | jcbb
#   loop_closure.enabled    false | true
# and pipeline.landmarks points+mecp (MECP association over nn), whose
# polygon counts are listed under each table.
# Each trajectory is scored with evaluate_relations (mean translational
# error over the log's relations, m). Prints two markdown tables, without
# and with loop closure, and writes them to OUT_DIR/table.md.
#
# usage: tools/dev/landmark_comparison.sh DEVEL_DIR [OUT_DIR]
#   DEVEL_DIR  a built workspace's devel folder (`make landmark-comparison`
#              builds the Release one and passes it)
#   OUT_DIR    default output/landmark_comparison
#   LOGS       logs to run (default: every NAME.orig.bag with a NAME.relations)
#   COMBOS     landmarks/method pairs to run (default: all seven)
#   ROOMS      true: association gated by rooms drawn from the mapped walls
#              (pipeline.rooms.enabled; needs wall landmarks)
#   LOOPS      loop closure settings to run (default: "false true")
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
root=$(cd "$(dirname "$0")/../.." && pwd)
devel=${1:?usage: landmark_comparison.sh DEVEL_DIR [OUT_DIR]}
out=${2:-$root/output/landmark_comparison}
data=${DATA_DIR:-$root/../shared/datasets}
bin=$devel/lib/ekf_slam
for tool in ekf_slam_offline evaluate_relations; do
  if [ ! -x "$bin/$tool" ]; then
    echo "landmark_comparison: $bin/$tool not built" >&2
    exit 1
  fi
done
if [ ! -d "$data" ]; then
  echo "landmark_comparison: $data not found (the shared datasets): nothing to run" >&2
  exit 1
fi
if [ -z "${LOGS:-}" ]; then
  LOGS=$(for bag in "$data"/*.orig.bag; do
    name=$(basename "$bag" .orig.bag)
    if [ -f "$data/$name.relations" ]; then echo "$name"; fi
  done)
fi
mkdir -p "$out"

score() {  # log trajectory -> mean translation error [m] (or "-")
  local result
  result=$("$bin/evaluate_relations" --relations "$data/$1.relations" --trajectory "$2" 2>/dev/null) ||
    { echo "-"; return; }
  echo "$result" | sed -n 's/.*translation: \([0-9.]*\) +- .*/\1/p'
}

# One run: log, landmarks, association, loop closure -> "scan_matched
# filtered live smoothed" errors.
run() {
  local log=$1 landmarks=$2 method=$3 loops=$4
  local name="$log-${landmarks//+/_}-$method-loops_$loops-rooms_${ROOMS:-false}"
  local dir=$out/runs/$name
  mkdir -p "$dir"
  printf 'pipeline:\n  landmarks: %s\n  rooms:\n    enabled: %s\nassociation:\n  method: %s\nloop_closure:\n  enabled: %s\n' \
    "$landmarks" "${ROOMS:-false}" "$method" "$loops" > "$dir/config.yaml"
  if ! "$bin/ekf_slam_offline" --bag "$data/$log.orig.bag" --out "$dir" --config "$dir/config.yaml" \
    --no-figures --no-maps > "$dir/run.log" 2>&1; then
    echo "landmark_comparison: $name failed ($dir/run.log)" >&2
    echo "- - - -"
    return
  fi
  local t scores=()
  for t in scan_matched filtered live smoothed; do
    scores+=("$(score "$log" "$dir/trajectory_$t.txt")")
  done
  echo "${scores[*]}"
}

table=$out/table.md
: > "$table"
for loops in ${LOOPS:-false true}; do
  {
    echo
    if [ "$loops" = false ]; then
      echo "Without loop closure (causal = the filter, trajectory_live.txt; final = trajectory_smoothed.txt), m:"
    else
      echo "With loop closure (filtered = trajectory_filtered.txt; causal = trajectory_live.txt; final = trajectory_smoothed.txt), m:"
    fi
    echo
    echo "| log | landmarks | association | scan-matched | filtered | causal | final |"
    echo "|---|---|---|---|---|---|---|"
  } | tee -a "$table"
  mecp_notes=()
  for log in $LOGS; do
    for combo in ${COMBOS:-points/nn points/jcbb points+lines/nn points+lines/jcbb \
      points+lines_theta/nn points+lines_theta/jcbb points+mecp/nn}; do
      landmarks=${combo%/*} method=${combo#*/}
      read -r matched filtered live smoothed < <(run "$log" "$landmarks" "$method" "$loops")
      echo "| $log | $landmarks | $method | $matched | $filtered | $live | $smoothed |" |
        tee -a "$table"
      if [ "$landmarks" = points+mecp ]; then
        mecp_notes+=("- $log: $(grep -h '^MECP association' \
          "$out/runs/$log-points_mecp-$method-loops_$loops-rooms_${ROOMS:-false}"/report.txt 2>/dev/null || echo '-')")
      fi
    done
  done
  if [ ${#mecp_notes[@]} -gt 0 ]; then
    { echo; printf '%s\n' "${mecp_notes[@]}"; } | tee -a "$table"
  fi
done
echo "landmark_comparison: $table" >&2
