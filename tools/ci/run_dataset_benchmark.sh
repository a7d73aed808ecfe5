#!/usr/bin/env bash
# make benchmark: offline SLAM on every real log in ../shared/datasets
# (each NAME.orig.bag with its NAME.relations), with the built-in defaults
# (no --config: they are config/ekf_slam.yaml), scored with the relation
# metric of Kuemmerle et al. 2009. One run per log, pinned to one core.
#
# Writes output/benchmark/<log>/ (trajectories, maps, figures, report.txt)
# and two tables:
#   summary.md  one line per log: raw odometry, causal (what the live node
#               publishes, trajectory_live.txt), final (trajectory_smoothed.txt),
#               wall-clock and peak memory;
#   details.md  every trajectory of every log (mean +- std, translation and
#               rotation, relations used).
#
# usage: [DATASETS="intel aces"] [CONFIG=file.yaml] run_dataset_benchmark.sh DEVEL_DIR [OUT_DIR]
set -euo pipefail
devel=${1:?usage: run_dataset_benchmark.sh DEVEL_DIR [OUT_DIR]}
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${2:-$root/output/benchmark}
data=${DATA_DIR:-$root/../shared/datasets}
bin=$devel/lib/ekf_slam
# The figures' script imports the package's Python tools (ekf_slam_tools).
set +u
# shellcheck disable=SC1091
source "$devel/setup.bash"
set -u
if [ ! -d "$data" ]; then
  echo "run_dataset_benchmark: $data not found (the datasets live beside the repository); nothing to do" >&2
  exit 0
fi
names=${DATASETS:-$(cd "$data" && for b in *.orig.bag; do n=${b%.orig.bag}; [ -f "$n.relations" ] && echo "$n"; done)}
config_args=()
[ -n "${CONFIG:-}" ] && config_args=(--config "$CONFIG")
mkdir -p "$out"
summary=$out/summary.md
details=$out/details.md
{
  echo "| log | raw odometry [m] | causal (live) [m] | final (smoothed) [m] | loop-closed graph [m] | wall-clock [s] | peak memory [MiB] |"
  echo "|---|---|---|---|---|---|---|"
} > "$summary"
{
  echo "| log | trajectory | relations used | translation [m] | rotation [deg] |"
  echo "|---|---|---|---|---|"
} > "$details"

score() {  # log trajectory-name -> "mean +- std" (translation), details line appended
  local name=$1 traj=$2 file=$out/$1/trajectory_$2.txt result used trans rot
  [ -f "$file" ] || { echo "-"; return; }
  result=$("$bin/evaluate_relations" --relations "$data/$name.relations" --trajectory "$file" \
           --label "$name $traj" 2>/dev/null)
  used=$(echo "$result" | sed -n 's/.*relations used \([0-9]* \/ [0-9]*\).*/\1/p')
  trans=$(echo "$result" | sed -n 's/.*translation: \([0-9.]* +- [0-9.]*\) m .*/\1/p')
  rot=$(echo "$result" | sed -n 's/.*rotation: *\([0-9.]* +- [0-9.]*\) deg.*/\1/p')
  echo "| $name | $traj | $used | $trans | $rot |" >> "$details"
  echo "$trans"
}

for name in $names; do
  bag=$data/$name.orig.bag
  [ -f "$bag" ] || { echo "run_dataset_benchmark: $bag missing, skipped" >&2; continue; }
  dir=$out/$name
  echo "== $name"
  taskset -c 0 "$bin/ekf_slam_offline" --bag "$bag" --out "$dir" "${config_args[@]}" \
    2> "$dir.stderr" | tee "$dir.log"
  wall=$(sed -n 's/^wall-clock: \([0-9.]*\) s.*/\1/p' "$dir/report.txt")
  mem=$(sed -n 's/.*peak memory: \([0-9.]*\) MiB.*/\1/p' "$dir/report.txt")
  odometry=$(score "$name" odometry)
  score "$name" scan_matched > /dev/null
  score "$name" filtered > /dev/null
  live=$(score "$name" live)
  score "$name" rts > /dev/null
  smoothed=$(score "$name" smoothed)
  optimized=$(score "$name" optimized)
  echo "| $name | $odometry | $live | $smoothed | $optimized | $wall | $mem |" >> "$summary"
done
echo
cat "$details"
echo
cat "$summary"
