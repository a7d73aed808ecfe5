// ekf_slam_node: live EKF-SLAM (see slam_node.h and docs/live_system.md).
// Exits with 1 and names the key when a parameter or the configuration file
// is invalid.
#include <ros/ros.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <stdexcept>

#include "ekf_slam_ros/slam_node/slam_node.h"

int main(int argc, char** argv) {
#ifdef __GLIBC__
  // Every thread allocates from the one main arena. glibc otherwise gives
  // the back end's and the live map's threads arenas of their own, and
  // malloc_trim, which the live map's thread calls after each map, cannot
  // shorten those: on a 30-minute soak with loop closure they grew by
  // 0.3 MiB a minute while the heap in use stayed flat (docs/robustness.md,
  // Soak). The main arena's free pages all go back. Set before any thread
  // starts; GLIBC_TUNABLES=glibc.malloc.arena_max does the same.
  mallopt(M_ARENA_MAX, 1);
#endif
  ros::init(argc, argv, "ekf_slam_node");
  ros::NodeHandle node, private_node("~");
  ekf_slam::SlamNodeParams params;
  std::string error;
  if (!ekf_slam::loadSlamNodeParams(private_node, &params, &error)) {
    ROS_FATAL("ekf_slam_node: %s", error.c_str());
    return 1;
  }
  ekf_slam::SlamConfig config;
  std::string source;
  if (!ekf_slam::loadNodeSlamConfig(private_node, params.config_file, &config, &source, &error)) {
    ROS_FATAL("ekf_slam_node: bad configuration %s:\n%s", source.c_str(), error.c_str());
    return 1;
  }
  ROS_INFO("ekf_slam_node: configuration from %s", source.c_str());
  if (params.input == "features" &&
      (config.pipeline.scan_matching.enabled || config.pipeline.loop_closure.enabled)) {
    const char* key =
        config.pipeline.scan_matching.enabled ? "scan_matching.enabled" : "loop_closure.enabled";
    ROS_FATAL(
        "ekf_slam_node: input is 'features' but %s is true in %s; it needs the raw scans: set it "
        "false there or use input: scan",
        key, source.c_str());
    return 1;
  }
  try {
    ekf_slam::SlamNode slam(node, private_node, params, config);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("ekf_slam_node: %s", e.what());
    return 1;
  }
  return 0;
}
