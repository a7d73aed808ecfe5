#!/usr/bin/env bash
# Runs every Google Benchmark executable in $1, writing JSON into $2.
set -euo pipefail
bin_dir=${1:?usage: run_benchmarks.sh BIN_DIR OUT_DIR}
out_dir=${2:?usage: run_benchmarks.sh BIN_DIR OUT_DIR}
mkdir -p "$out_dir"
shopt -s nullglob
for exe in "$bin_dir"/*; do
  [ -x "$exe" ] || continue
  name=$(basename "$exe")
  echo "== $name"
  taskset -c 0 "$exe" --benchmark_out="$out_dir/$name.json" --benchmark_out_format=json \
    ${BENCH_ARGS:-}
done
echo "benchmark JSON written to $out_dir"
