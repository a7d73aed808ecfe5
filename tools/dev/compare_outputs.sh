#!/usr/bin/env bash
# Compares two `make benchmark` output folders byte for byte: every
# trajectory, covariance, landmarks.yaml and map file of every log (the
# figures, logs and report.txt hold times and are left out). Used to show
# that a restructuring changes no result.
#
# usage: tools/dev/compare_outputs.sh BEFORE_DIR AFTER_DIR
#   (each holding <log>/trajectory_*.txt …, as output/benchmark does)
set -euo pipefail
before=${1:?usage: compare_outputs.sh BEFORE_DIR AFTER_DIR}
after=${2:?usage: compare_outputs.sh BEFORE_DIR AFTER_DIR}
same=0
differ=0
for file in $(cd "$before" && find . -mindepth 2 \( -name 'trajectory_*.txt' -o -name 'covariance_*.txt' \
    -o -name 'landmarks.yaml' -o -name 'map*.pgm' -o -name 'map*.yaml' -o -name 'first_last_scans.txt' \) | sort); do
  if [ ! -f "$after/$file" ]; then
    echo "missing in $after: $file"
    differ=$((differ + 1))
  elif cmp -s "$before/$file" "$after/$file"; then
    same=$((same + 1))
  else
    echo "differs: $file"
    differ=$((differ + 1))
  fi
done
echo "compare_outputs: $same identical, $differ different"
[ "$differ" -eq 0 ] && [ "$same" -gt 0 ]
