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
rm -rf "$ROS_HOME/log"
mkdir -p "$ROS_HOME"
( cd "$ws" && catkin_make run_tests -j1 ${CATKIN_TEST_ARGS:-} ) > "$ws/run_tests.log" 2>&1
status=$?
grep -E '^\[ *(RUN|  FAILED|  SKIPPED) *\]|^\[ROSTEST\]|^\[ROSUNIT\]|FAILURE|rostest.*failed' "$ws/run_tests.log" | grep -v '^\[ RUN' | tail -n 60 || true
if [ $status -ne 0 ]; then
  echo "run_tests: 'catkin_make run_tests' exited with $status; log: $ws/run_tests.log" >&2
  tail -n 30 "$ws/run_tests.log" >&2
fi
# A test program that crashed writes no results ("did not generate test
# results"); rostest's own log names the process and the signal it died of.
grep -h 'process has died.*exit code -' "$ROS_HOME"/log/rostest-*.log 2>/dev/null | cut -c1-240 | tail -n 20 || true
/usr/bin/python3 "$root/tools/ci/test_summary.py" "$results"
summary=$?
[ $status -ne 0 ] && exit $status
exit $summary
