// Node-level parameters of ekf_slam_node (frames, topics, tf waiting, publish
// rates): read from the private namespace and validated; an unknown key or a
// bad value stops the node with the key's name. The filter/feature
// parameters (config/ekf_slam.yaml format) go through the same loader as
// ekf_slam_offline: from the private namespace `~slam` when present (the
// launch files load the file there, so `rosparam get` shows every value),
// else from the file named by `config_file`.
// Every key, its unit and default: config/ekf_slam_node.yaml.
#pragma once

#include <ros/node_handle.h>

#include <string>

#include "ekf_slam_ros/offline/slam_config.h"

namespace ekf_slam {

struct SlamNodeParams {
  std::string config_file;  // config/ekf_slam.yaml format; empty: built-in defaults
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  std::string scan_topic = "scan";
  // "scan": LaserScans in, features extracted inside the node. "features":
  // ekf_slam/Features from feature_node (or any other extractor) in; needs
  // scan_matching.enabled false, and ~smooth then has no scans for a grid.
  std::string input = "scan";
  std::string features_topic = "features";
  double tf_timeout = 0.3;             // s a scan may wait for its transforms
  int scan_queue_size = 30;            // scans waiting for tf at most (oldest dropped)
  double tf_cache_time = 10.0;         // s of transforms buffered (tf2's default)
  double transform_tolerance = 0.1;    // s map→odom is future-dated by
  double tf_publish_rate = 20.0;       // Hz, map→odom re-publication
  int min_valid_readings = 10;         // fewer usable ranges: the scan is rejected
  double laser_pose_tolerance = 0.01;  // m / rad: larger base_link→laser change warns
  int nis_window = 100;                // matches in the NIS average on /diagnostics
  double ellipse_probability = 0.95;   // of the covariance ellipses drawn
  bool localize_only = false;          // start without adding landmarks
  bool start_paused = false;           // drop scans until ~resume (a recorder can start first)
  std::string initial_map;             // landmark map file loaded at start ("" none)
  double diagnostic_period = 1.0;      // s
  int path_max_poses = 10000;          // newest poses in `path` (0: all)
  // Newest scans whose history ~smooth re-solves (0: every scan, memory
  // then grows with the run). Older scans live on in the key scans (loop
  // closure on) or in an occupancy grid of their own (off).
  int history_max_scans = 10000;
  // s between occupancy grids on `map`, built in the background from the
  // loop-closed key scans (0: only on ~smooth). Needs loop closure on.
  double map_update_interval = 5.0;
  // s: a scan stamped further ahead of the clock (ros::Time::now(), sim
  // time included) is refused and counted, and never becomes the reference.
  double max_future_stamp = 1.0;
  // A second, rear laser (sensor_msgs/LaserScan): each scan is merged with
  // the rear scan nearest in time into one 360° scan about base_link
  // (ekf_slam_core/sensors/scan_merge.h). Empty: the scan alone. Needs
  // input "scan".
  std::string rear_scan_topic;
  double rear_scan_tolerance = 0.2;  // s: a rear scan further from the scan's stamp is not used
  // rad, bearing step of the merged scan; 0: the scan's own increment.
  double merged_angle_increment = 0.0;
};

// False with `error` naming the key (resolved name) on a bad or unknown key.
struct FeatureNodeParams {
  std::string config_file;  // its `features:` section is used; empty: defaults
  std::string scan_topic = "scan";
};

bool loadSlamNodeParams(const ros::NodeHandle& private_node, SlamNodeParams* params,
                        std::string* error);
bool loadFeatureNodeParams(const ros::NodeHandle& private_node, FeatureNodeParams* params,
                           std::string* error);

// The SLAM configuration of a node: from ~slam when that namespace exists,
// else from params.config_file, else the built-in defaults. `source`
// receives where it came from (for messages); false with `error` naming the
// key on a bad value.
bool loadNodeSlamConfig(const ros::NodeHandle& private_node, const std::string& config_file,
                        SlamConfig* config, std::string* source, std::string* error);
}  // namespace ekf_slam
