// Node-level parameters of ekf_slam_node (frames, topics, tf waiting, publish
// rates): read from the private namespace and validated; an unknown key or a
// bad value stops the node with the key's name. Each parameter is declared
// once, in visitFields() below: its name, its default (the member
// initializer), its unit and its bounds. The loaders walk that declaration:
// the parameter server's (ros_params/param_fields.h) and the YAML binder's
// (config/ekf_slam_node.yaml lists every key with its default, which
// slam_node_params_test.cc checks against it). Rules between fields are in
// problems(). The filter/feature parameters (config/ekf_slam.yaml format)
// go through the same loader as ekf_slam_offline: from the private
// namespace `~slam` when present (the launch files load the file there, so
// `rosparam get` shows every value), else from the file named by
// `config_file`.
#pragma once

#include <ros/node_handle.h>

#include <string>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/angle.h"
#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_ros/offline/slam_config.h"

namespace ekf_slam {

// A broken rule between parameters: the key to name, and why.
using ParamProblems = std::vector<std::pair<std::string, std::string>>;

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
  double tf_timeout = 0.3;   // s a scan may wait for its transforms
  int scan_queue_size = 30;  // scans waiting for tf at most (oldest dropped)
  // Inputs the subscription holds while the node is busy (beyond it the
  // oldest is discarded and counted), so it is ample.
  int subscriber_queue_size = 1000;
  double tf_cache_time = 10.0;  // s of transforms buffered (tf2's default)
  // When the clock jumps back (a bag replayed again, or looped with -l):
  // "new_map" starts a new map from the new data, as ~reset does;
  // "continue" keeps the map as the prior of a filter restarted at the
  // initial pose, where a replayed log starts again.
  std::string clock_jump = "new_map";
  // false: map → odom is not sent (another node, a localiser say, owns it);
  // poses, maps and services are unchanged.
  bool publish_tf = true;
  double transform_tolerance = 0.1;    // s map→odom is future-dated by
  double tf_publish_rate = 20.0;       // Hz, map→odom re-publication
  int min_valid_readings = 10;         // fewer usable ranges: the scan is rejected
  double laser_pose_tolerance = 0.01;  // m / rad: larger base_link→laser change warns
  // rad: a scan plane tilted further from the floor's (roll or pitch of
  // base_link → laser, upright or upside down) is reported on /diagnostics.
  double max_laser_tilt = 0.035;
  int nis_window = 100;               // matches in the NIS average on /diagnostics
  double ellipse_probability = 0.95;  // of the covariance ellipses drawn
  bool localize_only = false;         // start without adding landmarks
  // Localising in a state loaded by ~load_state: a robot whose scans stop
  // fitting the saved map is searched for over the whole map and moved
  // there when found (relocaliser.h).
  bool relocalise_when_lost = true;
  bool start_paused = false;  // drop scans until ~resume (a recorder can start first)
  std::string initial_map;    // landmark map file loaded at start ("" none)
  // A SLAM state (~write_state, ekf_slam_offline --save-state) loaded at
  // start, as ~load_state with localize_only as set ("" none).
  std::string initial_state;
  // Where the robot stands at start, in the map frame, and how sure that
  // is (variances; amcl's names): the first scan's pose.
  double initial_pose_x = 0.0, initial_pose_y = 0.0, initial_pose_a = 0.0;  // m, m, rad
  double initial_cov_xx = 0.0, initial_cov_yy = 0.0, initial_cov_aa = 0.0;  // m², m², rad²
  double diagnostic_period = 1.0;                                           // s
  int path_max_poses = 10000;  // newest poses in `path` (0: all)
  // Newest scans whose history ~smooth re-solves (0: every scan, memory
  // then grows with the run). Older scans live on in the key scans (loop
  // closure on) or in an occupancy grid of their own (off).
  int history_max_scans = 10000;
  // s between occupancy grids on `map`, built in the background from the
  // loop-closed key scans, or without loop closure from the scans (0: only
  // on ~smooth).
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

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.text("config_file", config_file, {});
    v.text("map_frame", map_frame, {});
    v.text("clock_jump", clock_jump, {"new_map", "continue"});
    v.text("odom_frame", odom_frame, {});
    v.text("base_frame", base_frame, {});
    v.text("scan_topic", scan_topic, {});
    v.text("input", input, {"scan", "features"});
    v.text("features_topic", features_topic, {});
    v.number("tf_timeout", tf_timeout, Bounds::closed(0.0, 60.0, "s"));
    v.integer("scan_queue_size", scan_queue_size, Bounds::closed(1, 10000, "scans"));
    v.integer("subscriber_queue_size", subscriber_queue_size,
              Bounds::closed(1, 100000, "messages"));
    v.number("tf_cache_time", tf_cache_time, Bounds::closed(1.0, 3600.0, "s"));
    v.flag("publish_tf", publish_tf);
    v.number("transform_tolerance", transform_tolerance, Bounds::closed(0.0, 10.0, "s"));
    v.number("tf_publish_rate", tf_publish_rate, Bounds::closed(0.1, 1000.0, "Hz"));
    v.integer("min_valid_readings", min_valid_readings, Bounds::closed(2, 100000, "readings"));
    v.number("laser_pose_tolerance", laser_pose_tolerance, Bounds::closed(0.0, 10.0, "m, rad"));
    v.number("max_laser_tilt", max_laser_tilt, Bounds::closed(0.0, 1.6, "rad"));
    v.integer("nis_window", nis_window, Bounds::closed(1, 1000000, "matches"));
    v.number("ellipse_probability", ellipse_probability, Bounds::closed(0.01, 0.9999));
    v.flag("localize_only", localize_only);
    v.flag("relocalise_when_lost", relocalise_when_lost);
    v.flag("start_paused", start_paused);
    v.text("initial_map", initial_map, {});
    v.text("initial_state", initial_state, {});
    v.number("initial_pose_x", initial_pose_x, Bounds::closed(-1e6, 1e6, "m"));
    v.number("initial_pose_y", initial_pose_y, Bounds::closed(-1e6, 1e6, "m"));
    v.number("initial_pose_a", initial_pose_a, Bounds::closed(-2.0 * kPi, 2.0 * kPi, "rad"));
    v.number("initial_cov_xx", initial_cov_xx, Bounds::closed(0.0, 1e6, "m²"));
    v.number("initial_cov_yy", initial_cov_yy, Bounds::closed(0.0, 1e6, "m²"));
    v.number("initial_cov_aa", initial_cov_aa, Bounds::closed(0.0, 100.0, "rad²"));
    v.number("diagnostic_period", diagnostic_period, Bounds::closed(0.01, 60.0, "s"));
    v.integer("path_max_poses", path_max_poses, Bounds::closed(0, 100000000, "poses"));
    v.integer("history_max_scans", history_max_scans, Bounds::closed(0, 100000000, "scans"));
    v.number("map_update_interval", map_update_interval, Bounds::closed(0.0, 3600.0, "s"));
    v.number("max_future_stamp", max_future_stamp, Bounds::closed(0.0, 1e6, "s"));
    v.text("rear_scan_topic", rear_scan_topic, {});
    v.number("rear_scan_tolerance", rear_scan_tolerance, Bounds::closed(0.0, 10.0, "s"));
    v.number("merged_angle_increment", merged_angle_increment,
             Bounds::closed(0.0, kPi / 4.0, "rad"));
  }
  // The rules between fields, and the texts that must not be empty.
  ParamProblems problems() const;
};

// False with `error` naming the key (resolved name) on a bad or unknown key.
struct FeatureNodeParams {
  std::string config_file;  // its `features:` section is used; empty: defaults
  std::string scan_topic = "scan";

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.text("config_file", config_file, {});
    v.text("scan_topic", scan_topic, {});
  }
  ParamProblems problems() const;
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
