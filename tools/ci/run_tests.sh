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
# Two lanes, one test at a time in each. Most of the rostests' time is
# wall-clock time of the simulated robot driving (its serial links run at the
# real baud rates; a lap takes minutes and a fraction of one core), so those
# tests share the machine with the rest: the other rostests and the gtests.
# A test drives the simulated robot when its launch file includes sim.launch.
# TEST_LANES=1 runs everything in one lane, as `catkin_make run_tests -j1`
# does.
# catkin's run_tests_<package>_<type>_<name> targets run one test each;
# unlike the _run_tests_* ones that `catkin_make run_tests` uses, they
# neither re-check the build of every test nor clear the results of the
# tests before them.
targets=$(make -C "$ws/build" help | sed -n 's/^\.\.\. \(run_tests_ekf_slam_\(gtest\|rostest\|roslaunch-check\)_.*\)$/\1/p')
drive=()
rest=()
for target in $targets; do
  test_file=""
  case $target in
    run_tests_ekf_slam_rostest_test_*) test_file="$root/test/${target#run_tests_ekf_slam_rostest_test_}" ;;
  esac
  if [ "${TEST_LANES:-2}" != 1 ] && [ -n "$test_file" ] && grep -q 'launch/sim.launch' "$test_file" 2>/dev/null; then
    drive+=("$target")
  else
    rest+=("$target")
  fi
done
echo "run_tests: ${#drive[@]} tests that drive the simulated robot beside ${#rest[@]} others; logs $ws/run_tests_*.log"
run_lane() {  # run_lane LOG TARGET...: each target in turn, on past failures
  local log=$1
  shift
  [ $# -eq 0 ] && return 0
  make -C "$ws/build" -k -j1 "$@" > "$log" 2>&1
}
run_lane "$ws/run_tests_drive.log" "${drive[@]}" &
drive_pid=$!
run_lane "$ws/run_tests_rest.log" "${rest[@]}"
status=$?
wait $drive_pid || status=$?
cat "$ws/run_tests_rest.log" "$ws/run_tests_drive.log" > "$ws/run_tests.log" 2>/dev/null
grep -E '^\[ *(RUN|  FAILED|  SKIPPED) *\]|^\[ROSTEST\]|^\[ROSUNIT\]|FAILURE|rostest.*failed' "$ws/run_tests.log" | grep -v '^\[ RUN' | tail -n 60 || true
if [ $status -ne 0 ]; then
  echo "run_tests: running the tests exited with $status; log: $ws/run_tests.log" >&2
  tail -n 30 "$ws/run_tests.log" >&2
fi
# A test program that crashed writes no results ("did not generate test
# results"); rostest's own log names the process and the signal it died of.
grep -h 'process has died.*exit code -' "$ROS_HOME"/log/rostest-*.log 2>/dev/null | cut -c1-240 | tail -n 20 || true
# Each test target leaves one result file (rosunit's are a rostest's
# inner report); fewer means results were lost, and the counts below are
# short by whatever they held.
expected=$(( ${#drive[@]} + ${#rest[@]} ))
found=$(find "$results" -name 'gtest-*.xml' -o -name 'rostest-*.xml' -o -name 'roslaunch-check*.xml' | wc -l)
if [ "$found" -lt "$expected" ]; then
  echo "run_tests: $found result files for $expected test targets: some results were lost" >&2
  lost=1
fi
/usr/bin/python3 "$root/tools/ci/test_summary.py" "$results"
summary=$?
[ "${lost:-0}" = 1 ] && summary=1
[ $status -ne 0 ] && exit $status
exit $summary
