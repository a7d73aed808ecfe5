#!/usr/bin/env bash
# make benchmark: offline EKF-SLAM on the real Pioneer + SICK logs in
# ../shared/datasets, scored with the relation metric (Kümmerle et al. 2009)
# for raw odometry, the scan-matched control, the filter, the RTS smoother, the full smoother
# and the loop-closed pose graph, with wall-clock and peak
# memory. Results go to output/benchmark/<dataset>/ and a summary table to
# output/benchmark/summary.md.
#
# usage: [DATASETS="intel aces"] run_dataset_benchmark.sh DEVEL_DIR [OUT_DIR] [CONFIG]
set -euo pipefail
devel=${1:?usage: run_dataset_benchmark.sh DEVEL_DIR [OUT_DIR] [CONFIG]}
root=$(cd "$(dirname "$0")/.." && pwd)
out=${2:-$root/output/benchmark}
config=${3:-$root/config/ekf_slam.yaml}
data=$root/../shared/datasets
bin=$devel/lib/ekf_slam
if [ ! -d "$data" ]; then
  echo "run_dataset_benchmark: $data not found (the datasets live beside the repository); nothing to do" >&2
  exit 0
fi
mkdir -p "$out"
summary=$out/summary.md
{
  echo "| dataset | trajectory | relations used | translation [m] | rotation [deg] | wall-clock [s] | processing [s] | real-time factor | peak memory [MiB] |"
  echo "|---|---|---|---|---|---|---|---|---|"
} > "$summary"
for name in ${DATASETS:-intel aces}; do
  bag=$data/$name.orig.bag
  rel=$data/$name.relations
  [ -f "$bag" ] || { echo "run_dataset_benchmark: $bag missing, skipped" >&2; continue; }
  dir=$out/$name
  echo "== $name"
  taskset -c 0 "$bin/ekf_slam_offline" --bag "$bag" --out "$dir" --config "$config" 2>/dev/null | tee "$dir.log"
  wall=$(sed -n 's/^wall-clock: \([0-9.]*\) s.*/\1/p' "$dir/report.txt")
  rtf=$(sed -n 's/.*real-time factor: \([0-9.]*\)x.*/\1/p' "$dir/report.txt")
  mem=$(sed -n 's/.*peak memory: \([0-9.]*\) MiB.*/\1/p' "$dir/report.txt")
  # processing: the run without the figures (drawn by Python inside the run)
  proc=$(sed -n 's/^processing: \([0-9.]*\) s.*/\1/p' "$dir/report.txt")
  # scan_matched: the laser front end's own track (the filter's control),
  # written only when scan matching is on.
  for traj in odometry scan_matched filtered rts smoothed optimized; do
    [ -f "$dir/trajectory_$traj.txt" ] || continue
    result=$("$bin/evaluate_relations" --relations "$rel" --trajectory "$dir/trajectory_$traj.txt" --label "$name $traj")
    echo "$result"
    used=$(echo "$result" | sed -n 's/.*relations used \([0-9]* \/ [0-9]*\).*/\1/p')
    trans=$(echo "$result" | sed -n 's/.*translation: \([0-9.]* +- [0-9.]*\) m .*/\1/p')
    rot=$(echo "$result" | sed -n 's/.*rotation: *\([0-9.]* +- [0-9.]*\) deg.*/\1/p')
    echo "| $name | $traj | $used | $trans | $rot | $wall | $proc | $rtf | $mem |" >> "$summary"
  done
done
echo
cat "$summary"
