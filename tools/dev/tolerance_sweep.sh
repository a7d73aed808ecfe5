#!/usr/bin/env bash
# Whether the final trajectory depends on where the full smoother's solve
# stops: each log is run with the built-in defaults but for the returned
# solve's relative-decrease tolerance (smoother.min_relative_decrease),
# from 1e-3 to 1e-8, with room for as many steps as it takes
# (smoother.max_iterations 400), and the final trajectory is scored with
# the relation metric. A well-posed problem gives the same figure at every
# tolerance; one whose cost is flat along some direction (a loop that is
# never closed) gives a figure that moves with it (docs/solvers.md).
#   tools/dev/tolerance_sweep.sh DEVEL_DIR [OUT_DIR]
# DATASETS="intel aces fr-clinic" by default; results in OUT_DIR (default
# output/tolerance_sweep/): tolerance_sweep.md, one row per log with the
# final error at each tolerance, the spread (largest over smallest) and the
# solver's steps; the runs' folders beside it. Exit code 1 when a log's
# spread exceeds 10 %.
set -euo pipefail
devel=${1:?usage: tolerance_sweep.sh DEVEL_DIR [OUT_DIR]}
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${2:-$root/output/tolerance_sweep}
data=${DATA_DIR:-$root/../shared/datasets}
bin=$devel/lib/ekf_slam
tolerances="1.0e-3 1.0e-4 1.0e-5 1.0e-6 1.0e-7 1.0e-8"
if [ ! -d "$data" ]; then
  echo "tolerance_sweep: $data not found (the datasets live beside the repository)" >&2
  exit 0
fi
mkdir -p "$out"
table=$out/tolerance_sweep.md
{
  printf "| log |"
  for t in $tolerances; do printf " %s [m] |" "$t"; done
  printf " spread | solver steps |\n|---|"
  for _ in $tolerances; do printf -- "---|"; done
  printf -- "---|---|\n"
} > "$table"

failed=0
for name in ${DATASETS:-intel aces fr-clinic}; do
  bag=$data/$name.orig.bag
  [ -f "$bag" ] || { echo "tolerance_sweep: $bag missing, skipped" >&2; continue; }
  row="| $name |"
  errors=()
  steps=()
  for t in $tolerances; do
    dir=$out/$name/$t
    mkdir -p "$dir"
    printf "smoother:\n  min_relative_decrease: %s\n  max_iterations: 400\n" "$t" > "$dir/config.yaml"
    echo "== $name, tolerance $t"
    "$bin/ekf_slam_offline" --bag "$bag" --out "$dir" --no-maps --config "$dir/config.yaml" \
      > "$dir/run.log" 2>&1
    error=$("$bin/evaluate_relations" --relations "$data/$name.relations" \
      --trajectory "$dir/trajectory_smoothed.txt" | sed -n 's/.*translation: \([0-9.]*\) +- .*/\1/p')
    errors+=("$error")
    steps+=("$(sed -n 's/^full smoother: .* \([0-9]*\) iterations.*/\1/p' "$dir/report.txt")")
    row="$row $error |"
  done
  spread=$(printf "%s\n" "${errors[@]}" | sort -g | sed -n '1p;$p' | paste -sd' ' |
    awk '{printf "%.1f %%", 100 * ($2 / $1 - 1)}')
  echo "$row $spread | $(IFS=/; echo "${steps[*]}") |" >> "$table"
  if awk -v s="${spread% %}" 'BEGIN { exit !(s > 10) }'; then
    echo "tolerance_sweep: $name's final error moves by $spread with the tolerance" >&2
    failed=1
  fi
done
cat "$table"
exit $failed
