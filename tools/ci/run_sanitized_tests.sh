#!/usr/bin/env bash
# Runs every gtest of a workspace built with -DEKF_SLAM_SANITIZE=ON (ASan +
# UBSan, `make sanitize`) and writes a summary. Any sanitizer report makes
# its test fail (halt_on_error), and so the script exit 1.
#   tools/ci/run_sanitized_tests.sh WS OUT_DIR
set -u
ws=${1:?usage: run_sanitized_tests.sh WS OUT_DIR}
out=${2:?usage: run_sanitized_tests.sh WS OUT_DIR}
mkdir -p "$out" && out=$(cd "$out" && pwd)
set +u  # ROS's setup scripts read unset variables
# shellcheck disable=SC1091
source "$ws/devel/setup.bash"
set -u
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
# The gtests catkin registered (rostests need a roscore and are left out).
mapfile -t tests < <(make -C "$ws/build" help | sed -n 's/^\.\.\. run_tests_ekf_slam_gtest_//p' | sort)
if [ ${#tests[@]} -eq 0 ]; then
  echo "run_sanitized_tests: no gtest registered in $ws/build" >&2
  exit 2
fi
summary=$out/summary.md
{
  echo "| test | seconds | result |"
  echo "|---|---|---|"
} > "$summary"
failed=0 passed=0 total_start=$(date +%s)
for name in "${tests[@]}"; do
  binary=$ws/devel/lib/ekf_slam/$name
  if [ ! -x "$binary" ]; then
    echo "| $name | - | not built |" >> "$summary"
    failed=$((failed + 1))
    continue
  fi
  start=$(date +%s)
  (cd "$out" && "$binary" --gtest_output="xml:$out/$name.xml" > "$out/$name.log" 2>&1)
  rc=$?
  elapsed=$(( $(date +%s) - start ))
  if [ $rc -eq 0 ] && ! grep -q -e "ERROR: AddressSanitizer" -e "runtime error:" "$out/$name.log"; then
    result=passed; passed=$((passed + 1))
  else
    result="FAILED (exit $rc, $out/$name.log)"; failed=$((failed + 1))
  fi
  echo "| $name | $elapsed | $result |" >> "$summary"
  echo "run_sanitized_tests: $name: $result (${elapsed} s)"
done
echo >> "$summary"
echo "$passed passed, $failed failed under ASan + UBSan in $(( $(date +%s) - total_start )) s" | tee -a "$summary"
[ $failed -eq 0 ]
