#!/usr/bin/env bash
# Consistency of the whole simulated system over several noise draws: one
# office loop per seed through sim.launch (simulator, the real drivers on
# pseudo-terminals, the SLAM node), each recorded to a bag, then every bag
# replayed offline (tools/analysis/replay_consistency.py) with the simulator's SLAM
# configuration, with the same configuration but first-estimates Jacobians
# off, and with features.point_model_sigma 0 (when the configuration has
# another value), printing the pose NEES and the position error per run and
# averaged over the runs against its 95 % band. One run's band is wide (its errors are correlated
# over the whole loop); the average over runs is the test. A lost run, whose
# robot was steered into a wall, is ended by sim_monitor.py after 30 s at
# rest and counted like any other (its report says "ended early").
#
# usage: office_monte_carlo.sh OUT_DIR [SEEDS]   (default seeds: "1 2 3 4 5")
# Takes about 2.5 minutes of real time per seed. Expects the workspace's
# setup.bash to be sourced.
set -euo pipefail
out=$(mkdir -p "${1:?usage: office_monte_carlo.sh OUT_DIR [SEEDS]}" && cd "$1" && pwd)
seeds=${2:-1 2 3 4 5}
root=$(cd "$(dirname "$0")/../.." && pwd)
config=$root/config/ekf_slam_sim.yaml
bags=()
failed=()
for seed in $seeds; do
  dir=$out/seed$seed
  mkdir -p "$dir"
  port=$((11600 + seed % 300))
  export ROS_MASTER_URI=http://localhost:$port ROS_HOME=$dir/ros_home
  echo "office_monte_carlo: seed $seed (master port $port)"
  roslaunch -p "$port" ekf_slam sim.launch world:=office waypoints:=office_loop seed:="$seed" \
    start_paused:=true link_dir:=/tmp/ekf_slam_mc_$port > "$dir/launch.log" 2>&1 &
  launch_pid=$!
  until rostopic list > /dev/null 2>&1; do sleep 0.5; done
  rosbag record -O "$dir/run.bag" /scan /odom /tf /tf_static /ground_truth/odom \
    __name:=mc_recorder > /dev/null 2>&1 &
  recorder_pid=$!
  status=0
  /usr/bin/python3 "$root/tools/dev/sim_monitor.py" --out "$dir" --world office --timeout 900 \
    --resume-after-recorder /mc_recorder > "$dir/monitor.log" 2>&1 || status=$?
  kill -INT "$recorder_pid" 2>/dev/null || true
  wait "$recorder_pid" 2>/dev/null || true
  kill -INT "$launch_pid" 2>/dev/null || true
  wait "$launch_pid" 2>/dev/null || true
  if [ $status -ne 0 ]; then
    # One seed lost (a node that died, a machine too loaded to start in
    # time) does not void the others: it is named and left out.
    echo "office_monte_carlo: seed $seed did not complete (see $dir/monitor.log and $dir/launch.log); left out" >&2
    failed+=("$seed")
    continue
  fi
  grep "average pose NEES\|ended early" "$dir/report.txt" | sed "s/^/  live: /"
  bags+=(--bag "$dir/run.bag")
done
if [ ${#bags[@]} -eq 0 ]; then
  echo "office_monte_carlo: no seed completed" >&2
  exit 1
fi
sed 's/first_estimate_jacobians: true/first_estimate_jacobians: false/' "$config" > "$out/standard_jacobians.yaml"
sed 's/point_model_sigma: [0-9.]*/point_model_sigma: 0.0/' "$config" > "$out/beam_noise_only.yaml"
echo "== replayed with config/ekf_slam_sim.yaml"
/usr/bin/python3 "$root/tools/analysis/replay_consistency.py" "${bags[@]}" --out "$out/replay" --config "$config"
echo "== the same with first_estimate_jacobians: false"
/usr/bin/python3 "$root/tools/analysis/replay_consistency.py" "${bags[@]}" --out "$out/replay_standard" \
  --config "$out/standard_jacobians.yaml"
if cmp -s "$config" "$out/beam_noise_only.yaml"; then
  echo "== (the configuration already has features.point_model_sigma: 0; not replayed again)"
else
  echo "== the same with features.point_model_sigma: 0 (beam noise only)"
  /usr/bin/python3 "$root/tools/analysis/replay_consistency.py" "${bags[@]}" --out "$out/replay_beam_noise_only" \
    --config "$out/beam_noise_only.yaml"
fi
if [ ${#failed[@]} -gt 0 ]; then
  echo "office_monte_carlo: ${#failed[@]} seed(s) did not complete: ${failed[*]}" >&2
  exit 1
fi
