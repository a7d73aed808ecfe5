#!/usr/bin/env bash
# Fails when catkin_lint (Debian catkin-lint) finds an error in the package
# (a dependency missing from package.xml or from catkin_package(), a
# misconfigured target). Warnings are counted, not fatal.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
if ! command -v catkin_lint > /dev/null; then
  echo "check_catkin_lint: catkin_lint not installed (tools/install_deps.sh installs catkin-lint)" >&2
  exit 1
fi
out=$(catkin_lint --pkg ekf_slam . 2>&1)
rc=$?
errors=$(grep -c ': error:' <<< "$out")
warnings=$(grep -c ': warning:' <<< "$out")
if [ $rc -ne 0 ] || [ "$errors" -gt 0 ]; then
  grep ': error:' <<< "$out" | sort -u >&2
  echo "check_catkin_lint: $errors errors" >&2
  exit 1
fi
echo "check_catkin_lint: no error ($warnings warnings: install rules are not written yet)"
