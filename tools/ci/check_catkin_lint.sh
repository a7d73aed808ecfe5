#!/usr/bin/env bash
# Fails when catkin_lint (Debian catkin-lint) finds an error or a warning in
# the package at its default level, with every check on: a dependency missing
# from package.xml or from catkin_package(), a target or a script that is not
# installed, a misconfigured target.
#
# The warnings that remain are listed below, one line each with its reason,
# and filtered by their exact message, never by check: any other warning,
# also one more of the same check, fails. So does a listed warning that no
# longer appears (the list is kept exact).
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
if ! command -v catkin_lint > /dev/null; then
  echo "check_catkin_lint: catkin_lint not installed (tools/ci/install_deps.sh installs catkin-lint)" >&2
  exit 1
fi

# Executable scripts that are not installed ("file '<path>' is executable
# but not installed"): <path>: <why it stays in the source tree>.
uninstalled_scripts=$(sed -e 's/[[:space:]]*#.*$//' -e '/^$/d' <<'EOF'
tools/ci/check_catkin_lint.sh      # make check: lints the source tree
tools/ci/check_core_ros_free.sh    # make check: greps the core's sources
tools/ci/check_format.sh           # make check / make format: the sources' formatting
tools/ci/check_layers.sh           # make check: greps the sources' includes
tools/ci/check_rosdep.sh           # make check: resolves the source tree's package.xml
tools/ci/install_deps.sh           # make: installs the Debian packages a build needs, before there is any
tools/ci/run_benchmarks.sh         # make bench: runs the bench workspace's benchmarks, never installed
tools/ci/run_dataset_benchmark.sh  # make benchmark: reads ../shared/datasets beside the checkout
tools/ci/run_demo.sh               # make demo: starts the source tree's tools/dev/sim_monitor.py
tools/ci/run_sim_scored.sh         # make demo and tools/dev: starts the source tree's tools/dev/sim_monitor.py
tools/ci/run_fuzzers.sh            # make fuzz: runs a fuzz workspace on test/fuzz_corpus
tools/ci/update_results_doc.py     # writes make benchmark's tables into the source tree's docs
tools/dev/landmark_comparison.sh   # make landmark-comparison: reads ../shared/datasets beside the checkout
tools/dev/line_experiment.sh       # make line-experiment: builds a workspace of the checkout
tools/dev/office_monte_carlo.sh    # runs the source tree's config/ and tools/ scripts
tools/dev/localization_check.sh    # starts the source tree's tools/dev/sim_monitor.py
tools/dev/mecp_sim_comparison.sh   # runs the source tree's config/ and tools/ci/run_sim_scored.sh
tools/dev/stage_comparison.sh      # reads ../shared/datasets beside the checkout
tools/dev/replay_screenshots.sh    # starts the source tree's tools/dev/rviz_screenshot.py, writes docs/images
tools/dev/continue_mapping_check.sh # reads ../shared/datasets beside the checkout
tools/dev/tolerance_sweep.sh       # reads ../shared/datasets beside the checkout
tools/dev/chapter5_figures.sh      # make figures: reads ../shared/datasets beside the checkout
tools/dev/compare_outputs.sh       # compares two benchmark output folders of the checkout
tools/dev/code_shape.py            # measures class, function and member-list sizes of the checkout
tools/dev/solver_comparison.sh     # builds a workspace of the checkout, reads ../shared/datasets
tools/dev/make_fuzz_seeds.py       # writes test/fuzz_corpus of the source tree
tools/dev/make_worlds.py           # writes config/worlds of the source tree
tools/dev/realtime_replay.py       # its default log is ../shared/datasets beside the checkout
tools/analysis/replay_consistency.py  # its default configuration is the source tree's config/
tools/analysis/sim_error_sources.py   # its default world is the source tree's config/worlds
# Installed, by ekf_slam_add_program_script (cmake/EkfSlamHelpers.cmake):
# catkin_lint does not read the body of a CMake function.
tools/analysis/plot_offline.py
tools/analysis/plot_scan_features.py
EOF
)
known=$(while read -r path; do
  echo "ekf_slam: warning: file '$path' is executable but not installed"
done <<< "$uninstalled_scripts" | sort -u)

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
out=$(catkin_lint "${rosdep_args[@]}" --pkg ekf_slam . 2>&1)
rc=$?
found=$(grep -E ': (error|warning):' <<< "$out" | sort -u)
problems=$(comm -23 <(echo "$found") <(echo "$known") | sed '/^$/d')
stale=$(comm -13 <(echo "$found") <(echo "$known") | sed '/^$/d')
status=0
if [ $rc -ne 0 ] || [ -n "$problems" ]; then
  [ -n "$problems" ] && echo "$problems" >&2
  [ $rc -ne 0 ] && echo "check_catkin_lint: catkin_lint exited with $rc:" >&2 && echo "$out" | tail -n 20 >&2
  echo "check_catkin_lint: $(grep -c . <<< "$problems") errors or warnings" >&2
  status=1
fi
if [ -n "$stale" ]; then
  echo "$stale" >&2
  echo "check_catkin_lint: these listed warnings no longer appear: remove them from tools/ci/check_catkin_lint.sh" >&2
  status=1
fi
[ $status -eq 0 ] && echo "check_catkin_lint: no error, no warning but the $(grep -c . <<< "$known") listed"
exit $status
