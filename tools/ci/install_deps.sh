#!/usr/bin/env bash
# Installs the Debian packages this project needs, only when one is missing.
# Idempotent and silent when everything is present. Needs root (or sudo).
# Extra packages a target needs (clang for `make fuzz`) come as arguments.
set -euo pipefail

PACKAGES=(
  # build
  build-essential cmake pkgconf catkin clang-format catkin-lint
  # ROS 1 from Debian
  ros-core-dev libroscpp-dev librosbag-dev librostest-dev python3-rostest rosbash
  libtf2-ros-dev libtf2-geometry-msgs-dev libsensor-msgs-dev libnav-msgs-dev
  libgeometry-msgs-dev libvisualization-msgs-dev libstd-srvs-dev
  libdiagnostic-updater-dev libdiagnostic-msgs-dev libtf2-msgs-dev
  ros-message-generation ros-message-runtime python3-rosbag python3-rospy
  # the messages the Python tools and rostests import (the -dev packages
  # above are C++ only)
  python3-std-msgs python3-std-srvs python3-geometry-msgs python3-nav-msgs
  python3-sensor-msgs python3-diagnostic-msgs python3-tf2-msgs
  # … and the rest of what package.xml's keys resolve to in Debian's rosdep
  # database (tools/ci/check_rosdep.sh holds the two lists equal)
  python3-visualization-msgs python3-diagnostic-updater python3-tf2 python3-tf2-ros
  python3-tf2-geometry-msgs ros-tf2-msgs python3-roslaunch python3-rostopic python3-rosunit
  python3-rosdep2
  # libraries
  libeigen3-dev libboost-dev libgtest-dev googletest libbenchmark-dev libyaml-cpp-dev
  libceres-dev
  # figures
  python3-matplotlib python3-numpy python3-pil python3-yaml
  # rviz (sim.launch rviz:=true) and its headless smoke test / screenshot
  rviz xvfb x11-apps
  # the robot's frames (robot.launch) and the description's check
  ros-robot-state-publisher liburdfdom-tools
  "$@"
)

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install_deps: installing missing Debian packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install_deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
# An apt cache that has never been filled finds nothing: update once.
if [ -z "$(ls -A /var/lib/apt/lists 2>/dev/null | grep -v -e lock -e partial)" ] ||
   ! apt-cache show "${missing[0]}" >/dev/null 2>&1; then
  $SUDO apt-get update -qq
fi
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install_deps: done"
