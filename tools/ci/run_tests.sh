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
# Lanes, one test at a time in each. Most of the time of the tests
# of the drivers and of the simulated robot is wall-clock time of serial
# links at their real baud rates (a lap of the simulated robot takes
# minutes and a fraction of one core): those tests, the real-time lane,
# share the machine with the rest, the other rostests (log replays, which
# want a core) and the gtests. The real-time lane: rostests whose launch
# file includes sim.launch, and every test of the driver packages (p3dx_*,
# lms200_*, serial_io, and the rostests of p3dx_driver and
# sick_lms200_driver). Each unattended exploration of a simulated world
# (test/explore_*.test: six to nine minutes of driving, a fifth of a core)
# is a lane of its own. TEST_LANES=1 runs everything in one lane, as
# `catkin_make run_tests -j1` does.
# catkin's run_tests_<package>_<type>_<name> targets run one test each;
# unlike the _run_tests_* ones that `catkin_make run_tests` uses, they
# neither re-check the build of every test nor clear the results of the
# tests before them.
targets=$(make -C "$ws/build" help | sed -n 's/^\.\.\. \(run_tests_ekf_slam_\(gtest\|rostest\|roslaunch-check\)_.*\)$/\1/p')
realtime=()
explore=()
rest=()
for target in $targets; do
  lane=rest
  case $target in
    run_tests_ekf_slam_rostest_test_explore_*)
      lane=explore ;;
    run_tests_ekf_slam_rostest_test_*)
      grep -q 'launch/sim.launch' "$root/test/${target#run_tests_ekf_slam_rostest_test_}" 2>/dev/null &&
        lane=realtime ;;
    run_tests_ekf_slam_gtest_p3dx_* | run_tests_ekf_slam_gtest_lms200_* | \
      run_tests_ekf_slam_gtest_serial_io_* | run_tests_ekf_slam_rostest_p3dx_driver_* | \
      run_tests_ekf_slam_rostest_sick_lms200_driver_*)
      lane=realtime ;;
  esac
  if [ "${TEST_LANES:-}" = 1 ]; then
    rest+=("$target")
  elif [ $lane = realtime ]; then
    realtime+=("$target")
  elif [ $lane = explore ]; then
    explore+=("$target")
  else
    rest+=("$target")
  fi
done
echo "run_tests: ${#realtime[@]} tests of the drivers and the simulated robot and ${#explore[@]} explorations beside ${#rest[@]} others; logs $ws/run_tests_*.log"
run_lane() {  # run_lane LOG TARGET...: each target in turn, on past failures
  local log=$1
  shift
  [ $# -eq 0 ] && return 0
  make -C "$ws/build" -k -j1 "$@" > "$log" 2>&1
}
run_lane "$ws/run_tests_realtime.log" "${realtime[@]}" &
realtime_pid=$!
explore_pids=()
explore_logs=()
for target in "${explore[@]}"; do
  explore_logs+=("$ws/run_tests_explore_${#explore_logs[@]}.log")
  run_lane "${explore_logs[-1]}" "$target" &
  explore_pids+=($!)
done
run_lane "$ws/run_tests_rest.log" "${rest[@]}"
status=$?
wait $realtime_pid || status=$?
for pid in "${explore_pids[@]}"; do
  wait "$pid" || status=$?
done
cat "$ws/run_tests_rest.log" "$ws/run_tests_realtime.log" "${explore_logs[@]}" \
  > "$ws/run_tests.log" 2>/dev/null
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
expected=$(( ${#realtime[@]} + ${#explore[@]} + ${#rest[@]} ))
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
