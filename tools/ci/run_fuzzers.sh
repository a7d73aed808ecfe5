#!/usr/bin/env bash
# Runs every libFuzzer target listed in FUZZ_DIR/fuzzers.txt (written by the
# -DEKF_SLAM_FUZZ=ON build) and writes a summary table.
#   tools/ci/run_fuzzers.sh FUZZ_DIR OUT_DIR [SECONDS] [RUNS]
# SECONDS (default 60) bounds each target's time; RUNS (default unbounded),
# when given, its number of inputs (libFuzzer -runs). The working corpus
# starts from the seeds in the repository (test/fuzz_corpus/<target>) and is
# kept in OUT_DIR/corpus/<target>, so a later campaign continues from it;
# crash reproducers land in OUT_DIR/artifacts/<target>/. FUZZ_TARGETS (in
# the environment), when set, names the targets to run (space-separated).
# Exit status 1 when any target found a crash, a leak or a timeout.
set -u
fuzz_dir=${1:?usage: run_fuzzers.sh FUZZ_DIR OUT_DIR [SECONDS] [RUNS]}
out=${2:?usage: run_fuzzers.sh FUZZ_DIR OUT_DIR [SECONDS] [RUNS]}
seconds=${3:-60}
runs=${4:-}
root=$(cd "$(dirname "$0")/../.." && pwd)
list=$fuzz_dir/fuzzers.txt
if [ ! -f "$list" ]; then
  echo "run_fuzzers: $list not found (build with -DEKF_SLAM_FUZZ=ON first)" >&2
  exit 2
fi
mkdir -p "$out"
summary=$out/summary${FUZZ_TARGETS:+-$(echo "$FUZZ_TARGETS" | tr " " "-")}.md
{
  echo "| target | seconds | inputs executed | inputs/s | corpus | coverage (edges) | findings |"
  echo "|---|---|---|---|---|---|---|"
} > "$summary"
failed=0
while read -r name corpus; do
  [ -n "$name" ] || continue
  if [ -n "${FUZZ_TARGETS:-}" ] && [[ " $FUZZ_TARGETS " != *" $name "* ]]; then continue; fi
  work=$out/corpus/$name
  artifacts=$out/artifacts/$name
  mkdir -p "$work" "$artifacts"
  log=$out/$name.log
  limits=(-max_total_time="$seconds")
  [ -n "$runs" ] && limits+=(-runs="$runs")
  echo "run_fuzzers: $name (${seconds} s${runs:+, at most $runs inputs})"
  start=$(date +%s)
  "$fuzz_dir/$name" "${limits[@]}" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$artifacts/" "$work" "$root/$corpus" > "$log" 2>&1
  rc=$?
  elapsed=$(( $(date +%s) - start ))
  executed=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  edges=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  files=$(find "$work" -type f | wc -l)
  found=$(find "$artifacts" -type f | wc -l)
  if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then
    failed=1
    finding="$found reproducer(s) in $artifacts (exit $rc; see $log)"
  else
    finding=none
  fi
  echo "| $name | $elapsed | ${executed:-?} | ${speed:-?} | $files | ${edges:-?} | $finding |" >> "$summary"
done < "$list"
cat "$summary"
exit $failed
