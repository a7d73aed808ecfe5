#!/usr/bin/env bash
# `make test` RUNS times in a row (3 by default) while BUSY busy loops (2:
# one per core of the reference machine) spin beside it: the tests must
# hold on a loaded machine. Prints each run's time and result and a summary
# line; exit code non-zero when any run failed. Logs in $OUT (default
# output/test_under_load/): run_<n>.log, and run_<n>/ with the run's test
# logs and results (the next run clears the workspace's).
#   tools/ci/test_under_load.sh [RUNS]
set -u
runs=${1:-3}
busy=${BUSY:-2}
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${OUT:-$root/output/test_under_load}
# The workspace make test uses (the Makefile's WS).
ws=${XDG_CACHE_HOME:-$HOME/.cache}/ekf_slam/$(printf %s "$root" | md5sum | cut -c1-12)/ws
mkdir -p "$out"
loops=()
for _ in $(seq "$busy"); do
  sh -c 'while :; do :; done' &
  loops+=($!)
done
trap 'kill "${loops[@]}" 2>/dev/null' EXIT
echo "test_under_load: $runs runs of make test beside $busy busy loops (pids ${loops[*]}); logs in $out"
failed=0
for run in $(seq "$runs"); do
  start=$(date +%s)
  make -C "$root" test > "$out/run_$run.log" 2>&1
  status=$?
  seconds=$(( $(date +%s) - start ))
  mkdir -p "$out/run_$run"
  cp "$ws"/run_tests*.log "$out/run_$run/" 2>/dev/null
  cp -r "$ws/build/test_results" "$ws/ros_home/log" "$out/run_$run/" 2>/dev/null
  summary=$(grep -E '^Summary:' "$out/run_$run.log" | tail -n 1)
  printf 'run %d: exit %d after %d min %02d s; %s\n' "$run" "$status" $((seconds / 60)) \
    $((seconds % 60)) "${summary:-no summary line}"
  [ $status -ne 0 ] && failed=$((failed + 1))
done
echo "Summary: $((runs - failed)) of $runs runs of make test passed beside $busy busy loops"
[ $failed -eq 0 ]
