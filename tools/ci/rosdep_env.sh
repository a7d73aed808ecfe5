# Sourced by tools/ci/check_rosdep.sh and tools/ci/check_catkin_lint.sh:
#   rosdep_env DIR
# points rosdep (and catkin_lint) at a private cache in DIR built from
# Debian's own rosdep database (python3-rosdep2; the ROS keys) and
# rosdep/debian.yaml (the system keys Debian's database lacks), with an empty
# local rosdistro index, so that nothing needs the internet and the machine's
# own rosdep setup is neither needed nor changed. Returns non-zero, with
# rosdep's output on stderr, when the cache cannot be built.
rosdep_env() {
  local dir=$1 root
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
  mkdir -p "$dir/sources.list.d"
  echo "yaml file://$root/rosdep/debian.yaml" > "$dir/sources.list.d/10-ekf_slam.list"
  echo "yaml file:///usr/share/python3-rosdep2/debian.yaml" > "$dir/sources.list.d/20-debian.list"
  printf '%%YAML 1.1\n---\ndistributions: {}\ntype: index\nversion: 4\n' > "$dir/index-v4.yaml"
  export ROSDEP_SOURCE_PATH="$dir/sources.list.d" ROSDISTRO_INDEX_URL="file://$dir/index-v4.yaml"
  export ROS_HOME="$dir/ros_home" ROS_DISTRO=debian
  if ! rosdep update > "$dir/update.log" 2>&1; then
    cat "$dir/update.log" >&2
    return 1
  fi
}
