#!/usr/bin/env bash
# Continue mapping on the shared logs: each log is mapped in one run, and
# again in two halves, the second resumed from the state the first saved
# (ekf_slam_offline --save-state / --resume). The resumed run's
# trajectories cover the whole log (the state carries the first half's
# history) and are scored like the one run's (causal: what the live node
# publishes; final: the full smoother), against the log's ground-truth
# relations. The second half is also localised in the first half's state
# with mapping off (--localize-only; the robot starts where the first half
# stopped, its true start pose), and again with no start pose (--global: it
# is found in the saved map from its first scans): their causal errors
# against the same half of the one run, and the scans the global start took.
# Last, the second half is mapped on its own (a state of its own) and the
# two halves' states are merged (ekf_slam_merge_states): the merged
# trajectory's final error against the one run's.
#   tools/dev/continue_mapping_check.sh DEVEL_DIR [OUT_DIR]
# DATASETS="intel aces" by default; results in OUT_DIR (default
# output/continue_mapping/): continue_mapping.md, and per log the runs'
# folders, and below the table the localised runs' fit to the saved map
# (tools/analysis/fit_outside_map.py: where the scans that do not fit were
# taken). Exit code 1 when a half-and-half error exceeds the one run's by
# more than 5 %, or the merged one by more than 10 %.
set -euo pipefail
devel=${1:?usage: continue_mapping_check.sh DEVEL_DIR [OUT_DIR]}
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${2:-$root/output/continue_mapping}
data=${DATA_DIR:-$root/../shared/datasets}
bin=$devel/lib/ekf_slam
if [ ! -d "$data" ]; then
  echo "continue_mapping_check: $data not found (the datasets live beside the repository)" >&2
  exit 0
fi
mkdir -p "$out"
table=$out/continue_mapping.md
{
  echo "| log | scans (first half) | causal: one run [m] | causal: two halves [m] | final: one run [m] | final: two halves [m] | final: two states merged [m] | loops: first half, at the end | second half causal: one run / localised / global [m] | global start found at scan |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
} > "$table"

mean() {  # relations trajectory -> mean translation error (m) over the relations it holds
  { "$bin/evaluate_relations" --relations "$1" --trajectory "$2" 2>/dev/null || true; } |
    sed -n 's/.*translation: \([0-9.]*\) +- .*/\1/p'
}

failed=0
fits=()
for name in ${DATASETS:-intel aces}; do
  bag=$data/$name.orig.bag
  relations=$data/$name.relations
  [ -f "$bag" ] || { echo "continue_mapping_check: $bag missing, skipped" >&2; continue; }
  dir=$out/$name
  mkdir -p "$dir"
  echo "== $name: one run"
  "$bin/ekf_slam_offline" --bag "$bag" --out "$dir/whole" --no-maps > "$dir/whole.log" 2>&1
  scans=$(sed -n 's/^scans: \([0-9]*\) .*/\1/p' "$dir/whole/report.txt")
  half=$((scans / 2))
  echo "== $name: the first $half scans, state saved"
  "$bin/ekf_slam_offline" --bag "$bag" --out "$dir/first" --no-maps --max-scans "$half" \
    --save-state "$dir/first.state" > "$dir/first.log" 2>&1
  echo "== $name: the rest, resumed"
  "$bin/ekf_slam_offline" --bag "$bag" --out "$dir/second" --no-maps --first-scan "$half" \
    --resume "$dir/first.state" > "$dir/second.log" 2>&1
  echo "== $name: the rest, localised in the first half's state"
  "$bin/ekf_slam_offline" --bag "$bag" --out "$dir/localised" --no-maps --first-scan "$half" \
    --resume "$dir/first.state" --localize-only > "$dir/localised.log" 2>&1
  echo "== $name: the rest, localised with no start pose"
  "$bin/ekf_slam_offline" --bag "$bag" --out "$dir/global" --no-maps --first-scan "$half" \
    --resume "$dir/first.state" --localize-only --global > "$dir/global.log" 2>&1 || true
  echo "== $name: the rest mapped on its own, and the two states merged"
  "$bin/ekf_slam_offline" --bag "$bag" --out "$dir/second_alone" --no-maps --first-scan "$half" \
    --save-state "$dir/second_alone.state" > "$dir/second_alone.log" 2>&1
  "$bin/ekf_slam_merge_states" "$dir/first.state" "$dir/second_alone.state" --out "$dir/merged" \
    > "$dir/merged.log" 2>&1 || true
  loops_first=$(sed -n 's/^loop closure: .* \([0-9]*\) loops accepted.*/\1/p' "$dir/first/report.txt" | head -n 1)
  loops_second=$(sed -n 's/^loop closure: .* \([0-9]*\) loops accepted.*/\1/p' "$dir/second/report.txt" | head -n 1)
  row="| $name | $half |"
  for kind in live smoothed; do
    one=$(mean "$relations" "$dir/whole/trajectory_$kind.txt")
    two=$(mean "$relations" "$dir/second/trajectory_$kind.txt")
    row="$row $one | $two |"
    if ! /usr/bin/python3 -c "import sys; sys.exit(0 if $two <= 1.05 * $one else 1)"; then
      echo "continue_mapping_check: $name $kind: two halves $two m against one run $one m (over 5 %)" >&2
      failed=1
    fi
  done
  if [ -f "$dir/merged/trajectory_merged.txt" ]; then
    merged=$(mean "$relations" "$dir/merged/trajectory_merged.txt")
    one=$(mean "$relations" "$dir/whole/trajectory_smoothed.txt")
    if ! /usr/bin/python3 -c "import sys; sys.exit(0 if $merged <= 1.10 * $one else 1)"; then
      echo "continue_mapping_check: $name merged: $merged m against one run $one m (over 10 %)" >&2
      failed=1
    fi
  else
    merged="not merged ($(tail -n 1 "$dir/merged.log"))"
    failed=1
  fi
  row="$row $merged |"
  # The second half of each run: its scans after the first half's last.
  end=$(awk '!/^#/ {t = $1} END {print t}' "$dir/first/trajectory_live.txt")
  second_half() {  # trajectory -> the same, from the second half's first scan on
    awk -v t="$end" '/^#/ || $1 > t' "$1" > "$1.second_half"
    echo "$1.second_half"
  }
  one_half=$(mean "$relations" "$(second_half "$dir/whole/trajectory_live.txt")")
  localised=$(mean "$relations" "$(second_half "$dir/localised/trajectory_live.txt")")
  if [ -f "$dir/global/report.txt" ]; then
    global=$(mean "$relations" "$(second_half "$dir/global/trajectory_live.txt")")
    found=$(sed -n 's/^global localisation: found at the log.s scan \([0-9]*\) .*/\1/p' "$dir/global/report.txt")
  else
    global="not found"
    found="- ($(tail -n 1 "$dir/global.log"))"
  fi
  echo "$row ${loops_first:-?}, ${loops_second:-?} | $one_half / $localised / $global | $found |" >> "$table"
  # The localised run's fit to the saved map (what the live node's lost
  # detector watches), and where the scans that do not fit were taken.
  fit_line=$(sed -n 's/^fit to the saved map (--localize-only): //p' "$dir/localised/report.txt")
  outside=$(/usr/bin/python3 "$root/tools/analysis/fit_outside_map.py" \
    "$dir/localised/fit_to_saved_map.txt" "$dir/whole/trajectory_smoothed.txt")
  fits+=("- $name, the second half localised: $fit_line; $outside")
done
echo
{
  echo
  printf '%s\n' "${fits[@]}"
} >> "$table"
cat "$table"
exit $failed
