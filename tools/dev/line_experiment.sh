#!/usr/bin/env bash
# The thesis's simulations of chapter 4 (docs/results.md, "Line landmarks
# in simulation" and "Rooms and MECP features in simulation"): builds
# ekf_slam_line_experiment and ekf_slam_rooms_experiment and runs each
# (§4.3.5 with the MECP variant of §4.4; §4.4.5 into OUT_DIR/rooms) with
# the default odometry noise and with the odometry noise's standard
# deviations tripled (the rooms also doubled); then the line experiment again under the thesis's
# own conditions (nearest-neighbour association of the points, walls
# measured from their two end readings, occlusion, steering by the
# estimate) into OUT_DIR/thesis_conditions, and plots all six.
#
# usage: line_experiment.sh OUT_DIR [DEVEL_DIR]
# With DEVEL_DIR (a catkin devel space that holds the built executable)
# nothing is built; otherwise a Release workspace under
# $XDG_CACHE_HOME/ekf_slam/<checkout>/line_ws is made and the one target is
# built there. RUNS (default 30) sets the Monte Carlo runs per variant of
# the line experiment, ROOMS_RUNS (default 20) per mode of the rooms one.
set -euo pipefail
export PATH=/usr/bin:/bin:$PATH
out=$(mkdir -p "${1:?usage: line_experiment.sh OUT_DIR [DEVEL_DIR]}" && cd "$1" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
runs=${RUNS:-30}
rooms_runs=${ROOMS_RUNS:-20}
if [ -n "${2:-}" ]; then
  bin=$2/lib/ekf_slam
else
  cache=${XDG_CACHE_HOME:-$HOME/.cache}/ekf_slam/$(printf %s "$root" | md5sum | cut -c1-12)
  ws=$cache/line_ws
  mkdir -p "$ws/src"
  [ -e "$ws/src/ekf_slam" ] || ln -s "$root" "$ws/src/ekf_slam"
  (cd "$ws" && catkin_make -j"${JOBS:-2}" -DPYTHON_EXECUTABLE=/usr/bin/python3 \
    -DCMAKE_BUILD_TYPE=Release -DCATKIN_ENABLE_TESTING=OFF ekf_slam_line_experiment \
    ekf_slam_rooms_experiment > "$ws/build.log" 2>&1) || { tail -n 60 "$ws/build.log"; exit 1; }
  bin=$ws/devel/lib/ekf_slam
fi
exe=$bin/ekf_slam_line_experiment
rooms_exe=$bin/ekf_slam_rooms_experiment
for e in "$exe" "$rooms_exe"; do
  [ -x "$e" ] || { echo "line_experiment: no executable at $e" >&2; exit 1; }
done
mkdir -p "$out/odometry_x3" "$out/rooms/odometry_x2" "$out/rooms/odometry_x3" \
  "$out/thesis_conditions/odometry_x3" \
  "$out/thesis_conditions/nn_odometry_x3"
echo "== default odometry noise ($runs runs per variant)"
"$exe" --out "$out" --runs "$runs"
/usr/bin/python3 "$root/tools/analysis/plot_line_experiment.py" "$out"
echo "== odometry noise x3"
"$exe" --out "$out/odometry_x3" --runs "$runs" --odometry-noise-scale 3
/usr/bin/python3 "$root/tools/analysis/plot_line_experiment.py" "$out/odometry_x3"
thesis_conditions=(--association nn --line-noise endpoints --occlusion --steer-by-estimate)
echo "== thesis conditions, default odometry noise"
"$exe" --out "$out/thesis_conditions" --runs "$runs" "${thesis_conditions[@]}"
/usr/bin/python3 "$root/tools/analysis/plot_line_experiment.py" "$out/thesis_conditions"
echo "== thesis conditions, odometry noise x3"
"$exe" --out "$out/thesis_conditions/odometry_x3" --runs "$runs" --odometry-noise-scale 3 \
  "${thesis_conditions[@]}"
/usr/bin/python3 "$root/tools/analysis/plot_line_experiment.py" "$out/thesis_conditions/odometry_x3"
echo "== nearest-neighbour association alone, odometry noise x3"
"$exe" --out "$out/thesis_conditions/nn_odometry_x3" --runs "$runs" --odometry-noise-scale 3 \
  --association nn
/usr/bin/python3 "$root/tools/analysis/plot_line_experiment.py" "$out/thesis_conditions/nn_odometry_x3"
echo "== rooms, default odometry noise ($rooms_runs runs per mode)"
"$rooms_exe" --out "$out/rooms" --runs "$rooms_runs"
/usr/bin/python3 "$root/tools/analysis/plot_rooms_experiment.py" "$out/rooms"
echo "== rooms, odometry noise x2 (where nearest neighbour starts to fail)"
"$rooms_exe" --out "$out/rooms/odometry_x2" --runs "$rooms_runs" --odometry-noise-scale 2
/usr/bin/python3 "$root/tools/analysis/plot_rooms_experiment.py" "$out/rooms/odometry_x2"
echo "== rooms, odometry noise x3"
"$rooms_exe" --out "$out/rooms/odometry_x3" --runs "$rooms_runs" --odometry-noise-scale 3
/usr/bin/python3 "$root/tools/analysis/plot_rooms_experiment.py" "$out/rooms/odometry_x3"
