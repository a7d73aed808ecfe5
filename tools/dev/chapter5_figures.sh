#!/usr/bin/env bash
# make figures: the experiments of the thesis's Chapter 5, redrawn by this
# system, into OUT (default output/figures), each figure beside the run it
# comes from:
#
#   loop_closing.png      Figs. 5.1-5.2: EKF-SLAM on a simulated landmark
#                         world (ekf_slam_sim_demo, 2 laps, unknown
#                         association, a 2 m sensor range so that the
#                         robot's uncertainty grows along the loop as in
#                         the thesis's run), the map one step before and
#                         one step after the loop closing
#   cartons.png           Fig. 5.4: the simulated carton layout driven once
#                         through the whole system (sim.launch): truth,
#                         odometry and SLAM paths, landmarks with ellipses
#   <log>_map.png         Figs. 5.6, 5.9: a real log offline, the grid and
#                         path with SLAM against odometry alone
#   <log>_first_last.png  Fig. 5.7: the first and last scans in the SLAM
#                         frame and in the odometry frame
#   <log>_smoothing.png   Figs. 5.11-5.12: the map before and after
#                         smoothing
#
# and OUT/figures.md, which lists them with each run's figures. The real
# logs (LOGS, default "intel aces") are read from ../shared/datasets; a
# log that is not there is skipped with a message.
#
# usage: [LOGS="intel aces"] chapter5_figures.sh DEVEL_DIR [OUT_DIR]
set -euo pipefail
devel=${1:?usage: chapter5_figures.sh DEVEL_DIR [OUT_DIR]}
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(mkdir -p "${2:-$root/output/figures}" && cd "${2:-$root/output/figures}" && pwd)
data=${DATA_DIR:-$root/../shared/datasets}
bin=$devel/lib/ekf_slam
set +u
# shellcheck disable=SC1091
source "$devel/setup.bash"
set -u
index=$out/figures.md
echo "# The thesis's Chapter 5, redrawn (tools/dev/chapter5_figures.sh)" > "$index"

echo "== Figs. 5.1-5.2: the loop closing on a simulated landmark world"
"$bin/ekf_slam_sim_demo" --out "$out/landmark_world" --laps 2 --max-range 2 > /dev/null
/usr/bin/python3 "$root/tools/analysis/plot_demo.py" "$out/landmark_world" > /dev/null
cp "$out/landmark_world/loop_closing.png" "$out/loop_closing.png"
{
  echo
  echo "## Figs. 5.1-5.2: loop closing (loop_closing.png)"
  echo '```'
  cat "$out/landmark_world/report.txt"
  echo '```'
} >> "$index"
grep "loop closing" "$out/landmark_world/report.txt"

echo "== Fig. 5.4: the carton layout through the whole system (a few minutes)"
mkdir -p "$out/cartons"
"$root/tools/ci/run_sim_scored.sh" cartons "$out/cartons" carton_layout \
  "${FIGURES_ROS_PORT:-11477}" ekf_slam sim.launch world:=carton_layout \
  waypoints:=carton_loop link_dir:=/tmp/ekf_slam_figures_$$
cp "$out/cartons/demo.png" "$out/cartons.png"
{
  echo
  echo "## Fig. 5.4: the carton layout (cartons.png)"
  echo '```'
  cat "$out/cartons/report.txt"
  echo '```'
} >> "$index"

for name in ${LOGS:-intel aces}; do
  bag=$data/$name.orig.bag
  if [ ! -f "$bag" ]; then
    echo "chapter5_figures: $bag not found (the datasets live beside the repository); $name skipped" >&2
    continue
  fi
  echo "== Figs. 5.6, 5.7, 5.11: $name offline"
  "$bin/ekf_slam_offline" --bag "$bag" --out "$out/$name" > "$out/$name.log" 2>&1
  cp "$out/$name/fig_map_slam_vs_odometry.png" "$out/${name}_map.png"
  cp "$out/$name/fig_first_last_scans.png" "$out/${name}_first_last.png"
  cp "$out/$name/fig_smoothing.png" "$out/${name}_smoothing.png"
  {
    echo
    echo "## Figs. 5.6, 5.7, 5.11: $name (${name}_map.png, ${name}_first_last.png, ${name}_smoothing.png)"
    echo '```'
    cat "$out/$name/report.txt"
    echo '```'
  } >> "$index"
done
echo "chapter5_figures: figures in $out (figures.md lists them)"
