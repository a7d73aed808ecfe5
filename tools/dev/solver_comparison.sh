#!/usr/bin/env bash
# The hand-written Levenberg–Marquardt solvers against Ceres on the real
# problems (docs/solvers.md): builds a Release workspace of its own, runs the
# offline runner on each log with --export-graphs, solves the exported
# loop-closure pose graph and full-smoother landmark graph with every solver
# (solver_comparison), scores each solution with the relation metric and
# prints one markdown table.
#
# usage: [LOGS="intel aces"] [CPU=1] tools/dev/solver_comparison.sh [OUT_DIR]
#   OUT_DIR   default output/solver_comparison (runs, exported problems,
#             one trajectory per solver, table.md)
#   LOGS      logs in ../shared/datasets (NAME.orig.bag + NAME.relations)
#   CPU       the one core every timed program is pinned to
#   SOLVER_BIN  a Release build's devel/lib/ekf_slam with solver_comparison
#             (make benchmark's, under ~/.cache/ekf_slam): used as it is,
#             no workspace of its own built
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-$root/output/solver_comparison}
data=${DATA_DIR:-$root/../shared/datasets}
ws=${SOLVER_WS:-${XDG_CACHE_HOME:-$HOME/.cache}/ekf_slam/solver_ws}
logs=${LOGS:-intel aces}
cpu=${CPU:-1}
# One thread everywhere: Ceres is told so, the BLAS under CHOLMOD too.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1

if [ -n "${SOLVER_BIN:-}" ]; then
  bin=$SOLVER_BIN
  # shellcheck disable=SC1091
  set +u; source "$bin/../../setup.bash"; set -u
else
  "$root/tools/ci/install_deps.sh"

  mkdir -p "$ws/src"
  if [ ! -e "$ws/src/ekf_slam" ]; then ln -s "$root" "$ws/src/ekf_slam"; fi
  if [ "$(readlink -f "$ws/src/ekf_slam")" != "$(readlink -f "$root")" ]; then
    echo "solver_comparison: $ws/src/ekf_slam links to another checkout; set SOLVER_WS" >&2
    exit 1
  fi
  echo "solver_comparison: building in $ws (log: $ws/build.log)" >&2
  (cd "$ws" && catkin_make -j1 -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=Release \
    -DEKF_SLAM_BUILD_BENCH=ON -DCATKIN_ENABLE_TESTING=OFF > "$ws/build.log" 2>&1) ||
    { tail -n 40 "$ws/build.log"; echo "solver_comparison: build failed" >&2; exit 1; }
  bin=$ws/devel/lib/ekf_slam
  if [ ! -x "$bin/solver_comparison" ]; then
    echo "solver_comparison: not built (Ceres not found by CMake?)" >&2
    exit 1
  fi
  set +u
  # shellcheck disable=SC1091
  source "$ws/devel/setup.bash"
  set -u
fi
mkdir -p "$out"

score() {  # log trajectory -> mean translation error [m] (or "-")
  local result
  result=$("$bin/evaluate_relations" --relations "$data/$1.relations" --trajectory "$2" 2>/dev/null) ||
    { echo "-"; return; }
  echo "$result" | sed -n 's/.*translation: \([0-9.]*\) +- .*/\1/p'
}

table=$out/table.md
{
  echo "| log | problem | solver | final cost | iterations | time [s] | translation error [m] | termination |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$table"
notes=()
for log in $logs; do
  bag=$data/$log.orig.bag
  if [ ! -f "$bag" ] || [ ! -f "$data/$log.relations" ]; then
    echo "solver_comparison: $bag or its .relations not found: $log skipped" >&2
    continue
  fi
  dir=$out/$log
  graphs=$dir/graphs
  mkdir -p "$graphs"
  echo "== $log: offline run" >&2
  taskset -c "$cpu" "$bin/ekf_slam_offline" --bag "$bag" --out "$dir" --no-figures \
    --export-graphs "$graphs" > "$dir.log" 2> "$dir.stderr" ||
    { echo "solver_comparison: offline run on $log failed ($dir.stderr)" >&2; continue; }
  for problem in pose_graph pose_graph_cold landmark_graph; do
    file=$graphs/$problem.txt
    if [ ! -f "$file" ]; then
      echo "solver_comparison: $log has no $problem (no loop closed?)" >&2
      continue
    fi
    case $problem in
      pose_graph*)
        kind=pose-graph scans=$graphs/pose_graph_scans.txt
        label="pose graph ($(grep -c '^NODE' "$file") nodes, $(grep -c '^EDGE' "$file") edges)"
        reference=$dir/trajectory_optimized.txt
        if [ "$problem" = pose_graph_cold ]; then
          label="$label, cold start" reference=""
        fi
        ;;
      *)
        kind=landmark-graph scans=$graphs/landmark_graph_scans.txt
        label="full smoother ($(grep -c '^POSE' "$file") poses, $(grep -c '^LANDMARK ' "$file")"
        label+=" landmarks, $(grep -c -e '^OBSERVATION' -e '^RELATIVE' -e '^PRIOR' "$file") edges)"
        reference=$dir/trajectory_smoothed.txt
        ;;
    esac
    echo "== $log: $problem" >&2
    results=$dir/$problem.tsv
    # Each problem's trajectories in a folder of its own (the names repeat).
    mkdir -p "$dir/$problem"
    taskset -c "$cpu" "$bin/solver_comparison" "--$kind" "$file" --scans "$scans" \
      --out "$dir/$problem" > "$results"
    while IFS=$'\t' read -r solver cost iterations seconds trajectory termination; do
      echo "| $log | $label | $solver | $cost | $iterations | $seconds | $(score "$log" "$trajectory") | $termination |" >> "$table"
      if [ "$solver" = "hand-written LM" ] && [ -n "$reference" ]; then
        if cmp -s "$trajectory" "$reference"; then
          notes+=("$log $problem: the hand-written solve of the export reproduces $(basename "$reference") byte for byte")
        else
          notes+=("$log $problem: the hand-written solve of the export DIFFERS from $(basename "$reference")")
        fi
      fi
    done < "$results"
  done
done
echo
cat "$table"
echo
for n in "${notes[@]}"; do echo "- $n"; done
