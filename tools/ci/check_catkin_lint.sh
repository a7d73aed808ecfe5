#!/usr/bin/env bash
# Fails when catkin_lint (Debian catkin-lint) finds an error or a warning in
# the package: a dependency missing from package.xml or from catkin_package(),
# a target that is not installed, a misconfigured target. Two checks are
# switched off, each for a reason that holds for this package:
#   external_interface_path: the static libraries that carry ROS include
#     paths to their users (lms200_ros, ros_params, conversions, …) are
#     internal and never exported; catkin_package() exports ekf_slam_core
#     only, and it has no such path.
#   uninstalled_script: tools/ holds developer and CI scripts run from the
#     source tree; the scripts a program starts are installed beside it
#     (ekf_slam_add_program_script).
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
if ! command -v catkin_lint > /dev/null; then
  echo "check_catkin_lint: catkin_lint not installed (tools/ci/install_deps.sh installs catkin-lint)" >&2
  exit 1
fi
# With the rosdep database (tools/ci/rosdep_env.sh) catkin_lint also checks that
# every dependency is a known key; without python3-rosdep2 it cannot.
rosdep_args=()
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# shellcheck source=tools/ci/rosdep_env.sh
source "$root/tools/ci/rosdep_env.sh"
if command -v rosdep > /dev/null && rosdep_env "$tmp" 2> /dev/null; then
  rosdep_args=(--rosdistro debian)
else
  echo "check_catkin_lint: rosdep not usable (apt-get install python3-rosdep2): dependency keys not checked" >&2
fi
out=$(catkin_lint "${rosdep_args[@]}" --pkg ekf_slam --ignore external_interface_path --ignore uninstalled_script . 2>&1)
rc=$?
problems=$(grep -E ': (error|warning):' <<< "$out" | sort -u)
if [ $rc -ne 0 ] || [ -n "$problems" ]; then
  echo "$problems" >&2
  echo "check_catkin_lint: $(grep -c . <<< "$problems") errors or warnings" >&2
  exit 1
fi
echo "check_catkin_lint: no error, no warning"
