#!/usr/bin/env bash
# Runs every gtest and rostest of the built workspace $1 and prints the
# summary line. Exit code non-zero on any failure.
set -o pipefail
ws=${1:?usage: run_tests.sh WORKSPACE}
root=$(cd "$(dirname "$0")/../.." && pwd)
results="$ws/build/test_results"
rm -rf "$results"
# shellcheck disable=SC1091
source "$ws/devel/setup.bash"
export ROS_HOME="$ws/ros_home"
mkdir -p "$ROS_HOME"
( cd "$ws" && catkin_make run_tests -j1 ${CATKIN_TEST_ARGS:-} ) > "$ws/run_tests.log" 2>&1
status=$?
grep -E '^\[ *(RUN|  FAILED|  SKIPPED) *\]|^\[ROSTEST\]|^\[ROSUNIT\]|FAILURE|rostest.*failed' "$ws/run_tests.log" | grep -v '^\[ RUN' | tail -n 60 || true
if [ $status -ne 0 ]; then
  echo "run_tests: 'catkin_make run_tests' exited with $status; log: $ws/run_tests.log" >&2
  tail -n 30 "$ws/run_tests.log" >&2
fi
/usr/bin/python3 "$root/tools/ci/test_summary.py" "$results"
summary=$?
[ $status -ne 0 ] && exit $status
exit $summary
