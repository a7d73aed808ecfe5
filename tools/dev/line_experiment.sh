#!/usr/bin/env bash
# The thesis's line-feature simulation (§4.3.5; docs/results.md, "Line
# landmarks in simulation"): builds ekf_slam_line_experiment, runs it with
# the default odometry noise and with the odometry noise's standard
# deviations tripled, and plots both.
#
# usage: line_experiment.sh OUT_DIR [DEVEL_DIR]
# With DEVEL_DIR (a catkin devel space that holds the built executable)
# nothing is built; otherwise a Release workspace under
# $XDG_CACHE_HOME/ekf_slam/<checkout>/line_ws is made and the one target is
# built there. RUNS (default 30) sets the Monte Carlo runs per variant.
set -euo pipefail
export PATH=/usr/bin:/bin:$PATH
out=$(mkdir -p "${1:?usage: line_experiment.sh OUT_DIR [DEVEL_DIR]}" && cd "$1" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
runs=${RUNS:-30}
if [ -n "${2:-}" ]; then
  exe=$2/lib/ekf_slam/ekf_slam_line_experiment
else
  cache=${XDG_CACHE_HOME:-$HOME/.cache}/ekf_slam/$(printf %s "$root" | md5sum | cut -c1-12)
  ws=$cache/line_ws
  mkdir -p "$ws/src"
  [ -e "$ws/src/ekf_slam" ] || ln -s "$root" "$ws/src/ekf_slam"
  (cd "$ws" && catkin_make -j"${JOBS:-2}" -DPYTHON_EXECUTABLE=/usr/bin/python3 \
    -DCMAKE_BUILD_TYPE=Release -DCATKIN_ENABLE_TESTING=OFF ekf_slam_line_experiment \
    > "$ws/build.log" 2>&1) || { tail -n 60 "$ws/build.log"; exit 1; }
  exe=$ws/devel/lib/ekf_slam/ekf_slam_line_experiment
fi
[ -x "$exe" ] || { echo "line_experiment: no executable at $exe" >&2; exit 1; }
mkdir -p "$out/odometry_x3"
echo "== default odometry noise ($runs runs per variant)"
"$exe" --out "$out" --runs "$runs"
/usr/bin/python3 "$root/tools/analysis/plot_line_experiment.py" "$out"
echo "== odometry noise x3"
"$exe" --out "$out/odometry_x3" --runs "$runs" --odometry-noise-scale 3
/usr/bin/python3 "$root/tools/analysis/plot_line_experiment.py" "$out/odometry_x3"
