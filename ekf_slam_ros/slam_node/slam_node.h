// ekf_slam_node: the live EKF-SLAM node, a thin shell around SlamPipeline
// (the same object the offline runner uses, so a bag gives the same answer
// live and offline).
//
// Data flow per scan (all callbacks on one thread, ros::spin; tf arrives
// through GuardedTfListener's thread, which refuses future stamps):
//   scan → checks (stamp after the last one, enough valid readings, geometry)
//        → tf2_ros::MessageFilter until odom → laser (odom→base_link and
//          base_link→laser) exists at the scan's stamp, at most
//          scan_queue_size scans: a transform never received, or
//          base_link→laser late, is waited for at most tf_timeout (then
//          dropped and logged); odometry that has paused (logs record only
//          motion) is waited for until its next sample
//        → SlamPipeline::processScan(scan, odometry)
//        → tf map→odom, pose, path, landmarks, landmark_map, association.
// With input: features the node takes ekf_slam/Features (feature_node's
// output, stamped and framed as the scan) instead: checks (known kinds,
// finite values, positive-definite covariances, stamp order) → the same
// queue → SlamPipeline::processFeatures → the same outputs.
// With a rear laser (~rear_scan_topic) each scan, once released, is merged
// with the rear scan nearest in time (slam_node_rear.cc): both mounts from
// tf, the robot's motion between the two stamps from odom → base_link; the
// pipeline then maps the merged 360° scan from a laser at base_link.
// Nothing is written back into the robot (thesis §3.4.2): the map frame
// is a separate estimate published as map → odom (REP-105).
// Every output is stamped with the scan's stamp (data time), so bag replay
// with use_sim_time gives the same stamps as the live run.
// Topics, services and parameters: docs/live_system.md. The class is
// spread over one file per concern: slam_node_input.cc, slam_node.cc
// (processing), slam_node_outputs.cc, slam_node_services.cc and
// slam_node_diagnostics.cc.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ekf_slam/Features.h>
#include <ekf_slam/LoadMap.h>
#include <ekf_slam/SaveMap.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_broadcaster.h>

#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/filter/line_support.h"
#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_core/sensors/scan_merge.h"
#include "ekf_slam_ros/offline/slam_config.h"
#include "ekf_slam_ros/slam_node/guarded_tf_listener.h"
#include "ekf_slam_ros/slam_node/live_map.h"
#include "ekf_slam_ros/slam_node/processing_times.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"

namespace ekf_slam {

// Why an input was not used; each reason is a counter on /diagnostics.
enum class DropReason {
  kStampNotIncreasing,     // stamp not after the last accepted scan's
  kStampInFuture,          // stamp more than max_future_stamp ahead of the clock
  kTooFewValidReadings,    // NaN / no-return scan
  kBadScanGeometry,        // angle_increment 0, NaN angles, ...
  kOdomTransformMissing,   // odom → base_link never received within tf_timeout, or silent
                           // while scan_queue_size newer scans arrived
  kLaserTransformMissing,  // base_link → laser not available at the stamp within tf_timeout
  kQueueOverflow,          // more scans waiting for tf than scan_queue_size
  kPaused,                 // the pause service was called
  kBadFeatures,            // a features message with unknown kinds or unusable values
};
constexpr DropReason kAllDropReasons[] = {
    DropReason::kStampNotIncreasing,   DropReason::kStampInFuture,
    DropReason::kTooFewValidReadings,  DropReason::kBadScanGeometry,
    DropReason::kOdomTransformMissing, DropReason::kLaserTransformMissing,
    DropReason::kQueueOverflow,        DropReason::kPaused,
    DropReason::kBadFeatures,
};
const char* toString(DropReason reason);

class SlamNode {
 public:
  // Parameters and configuration must be valid (loaded by their loaders).
  SlamNode(ros::NodeHandle node, ros::NodeHandle private_node, const SlamNodeParams& params,
           const SlamConfig& config);

 private:
  // One input waiting in the message filter for its transforms: a scan, or
  // features extracted from one (input: features), with the scan's header.
  struct PendingInput {
    std_msgs::Header header;
    std::optional<Scan> scan;
    std::optional<FeatureSet> features;
    ros::Time received;             // for the tf wait (clock time: data or sim)
    const void* message = nullptr;  // the message the filter holds (identity only)
    bool ready = false;             // its transforms exist; processed once the older ones are
    bool expired = false;           // dropped and counted; ignored on release
  };

  // --- input (slam_node_input.cc): checks, the queue waiting for tf, drops.
  void onScan(const sensor_msgs::LaserScan::ConstPtr& message);
  void onFeatures(const Features::ConstPtr& message);
  // rviz's "2D Pose Estimate": the filter restarts at the given pose, the
  // current landmarks (or the loaded map) as its prior.
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped& message);
  // Common to both inputs: the clock and pause checks (false: dropped).
  bool acceptingInput();
  // Hands a checked input to its message filter (`add`: the filter's add
  // for the message), or drops it for its stamp.
  void enqueue(PendingInput pending, const std::function<void()>& add);
  // The message filter's verdicts, on the node's thread: the transforms
  // exist at the input's stamp, or it was dropped (queue full, too old).
  void onTransformsReady(const void* message);
  // Processes the ready inputs at the head of the queue, in arrival order.
  void releaseInOrder();
  void processReleased(const PendingInput& pending);
  void onTransformsFailed(const void* message, tf2_ros::FilterFailureReason reason);
  // Drops (and counts, once) inputs that have waited longer than tf_timeout
  // for a transform that is missing rather than merely behind.
  void expireWaiting();
  // Empties both message filters and the inputs waiting in them.
  void clearWaiting();
  // The transform target → source at `stamp`; false with a description of
  // what is missing (frames, how late) in `why`. `behind` (optional) is set
  // when the transform exists but its newest sample is older than `stamp`:
  // its publisher is alive and the scan waits for the next sample.
  bool lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
              Pose2* pose, std::string* why, bool* behind = nullptr) const;
  void drop(DropReason reason, const std::string& detail);

  // --- rear laser (slam_node_rear.cc): ~rear_scan_topic merged into each scan.
  void onRearScan(const sensor_msgs::LaserScan::ConstPtr& message);
  // Processes `pending` (a released scan; `odometry` odom → base_link and
  // `front_mount` base_link → its frame at its stamp) merged with the rear
  // scan nearest in time, or alone (counted) when there is none within
  // rear_scan_tolerance or its transforms are missing. Either way the
  // pipeline gets a 360° scan about base_link and the identity laser pose.
  void processWithRear(const PendingInput& pending, const Pose2& odometry,
                       const Pose2& front_mount);

  // --- processing (slam_node.cc): the pipeline and one input through it.
  void createPipeline(const Pose2& laser_pose);
  void process(const PendingInput& pending, const Pose2& odometry, const Pose2& laser);
  void resetState();

  // --- outputs (slam_node_outputs.cc): map → odom, paths, maps.
  // new_estimate: map_to_odom_ was just updated from a scan, and goes out
  // even when the timer already used a newer stamp.
  void publishMapToOdom(const ros::Time& data_stamp, bool new_estimate = false);
  void onTfTimer(const ros::TimerEvent&);
  void publishLoopClosedPath(const ros::Time& data_stamp);
  void onMapTimer(const ros::TimerEvent&);
  void publishLandmarkMap(const std_msgs::Header& header);
  // The seen extent and endpoints of the pipeline's line landmarks, for
  // the map file, the LandmarkMap message and the markers.
  const std::unordered_map<int, LineSupport>& lineSupport() const;
  // The grid last published on `map` (live map, ~smooth or a loaded map);
  // false when there is none.
  bool currentGrid(nav_msgs::OccupancyGrid* map) const;
  void publishNodeGrid(const nav_msgs::OccupancyGrid& map);

  // --- services (slam_node_services.cc).
  bool onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  // Supervised step mode (thesis §3.4.3): one iteration on the next scan,
  // then paused again; the move made while paused is control, not a jump.
  bool onStep(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onSmooth(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onSaveMap(SaveMap::Request& request, SaveMap::Response& response);
  bool onLoadMap(LoadMap::Request& request, LoadMap::Response& response);
  // The pose (map frame) and covariance the next pipeline starts at; empty
  // when the pose and covariance are unusable, else the problem.
  std::string setStartPose(const Pose2& pose, const Matrix3& covariance);

  // --- diagnostics (slam_node_diagnostics.cc).
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  SlamNodeParams params_;
  SlamConfig config_;
  ros::NodeHandle node_;
  ros::NodeHandle private_node_;

  tf2_ros::Buffer tf_buffer_;
  GuardedTfListener tf_listener_;  // refuses future-stamped and invalid transforms
  tf2_ros::TransformBroadcaster tf_broadcaster_;

  ros::Subscriber input_subscriber_, initial_pose_subscriber_;
  ros::Publisher pose_publisher_, path_publisher_, landmarks_publisher_, landmark_map_publisher_,
      association_publisher_, smoothed_path_publisher_, map_publisher_, odometry_path_publisher_,
      loop_closed_path_publisher_;
  std::vector<ros::ServiceServer> services_;
  ros::Timer tf_timer_, drain_timer_, diagnostic_timer_, map_timer_;
  std::unique_ptr<LiveMapPublisher> live_map_;  // null when map_update_interval is 0
  long optimisations_published_ = 0;            // back-end optimisations seen by the path
  long optimisations_mapped_ = -1;              // … and by the last grid handed to live_map_
  int keys_mapped_ = 0;                         // key scans in that grid
  diagnostic_updater::Updater diagnostics_;

  // SLAM state. The pipeline is created at the first scan, when the laser
  // pose is known (from the configuration or tf).
  std::unique_ptr<SlamPipeline> pipeline_;
  std::optional<Pose2> laser_pose_;             // base_link → laser the pipeline uses
  std::optional<LandmarkMapFile> seed_map_;     // a loaded map waiting for the pipeline
  std::optional<Pose2> start_pose_;             // where that pipeline starts (map frame) …
  Matrix3 start_covariance_ = Matrix3::Zero();  // … and how sure that is
  long relocalisations_ = 0;                    // /initialpose messages taken
  // The grid the node published itself (~smooth, ~load_map) and when; the
  // live map keeps its own. A grid loaded for localisation stays on `map`:
  // the live map does not replace it.
  std::optional<nav_msgs::OccupancyGrid> node_grid_;
  std::chrono::steady_clock::time_point node_grid_time_;
  bool hold_loaded_grid_ = false;
  bool localize_only_ = false;
  bool paused_ = false;
  bool step_pending_ = false;  // ~step: pause again after the next scan
  long steps_done_ = 0;
  // Inputs wait for their transforms in a tf2_ros::MessageFilter (target
  // odom_frame, so that both odom → base_link and base_link → laser must
  // exist at the stamp); `waiting_` holds what the node knows of each, in
  // arrival order.
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::LaserScan>> scan_filter_;
  std::unique_ptr<tf2_ros::MessageFilter<Features>> features_filter_;
  std::deque<PendingInput> waiting_;
  std::optional<ros::Time> last_accepted_stamp_;  // newest scan let into the filter
  nav_msgs::Path path_;
  // The robot's own odometry drawn in the map frame, tied to the SLAM pose at
  // the first scan: where the robot would believe it is without SLAM.
  nav_msgs::Path odometry_path_;
  std::optional<Pose2> odometry_anchor_;  // map → odom at the first scan
  std::string laser_frame_;
  ros::Time last_scan_stamp_;  // of the last processed scan
  ros::Time last_clock_;       // ros::Time::now() at the last scan (jump-back detection)
  ros::Time last_tf_stamp_;    // map→odom stamp last sent (before the tolerance)
  bool have_map_to_odom_ = false;
  Pose2 map_to_odom_;

  // Diagnostics.
  std::map<DropReason, long> drops_;
  struct DropLog {
    ros::WallTime time;   // of the last line logged for the reason
    long suppressed = 0;  // drops not logged since
  };
  std::map<DropReason, DropLog> last_drop_log_;
  long scans_received_ = 0;
  // Wall time of each input's processing (pipeline and publication; not the
  // tf wait before it), over the whole run.
  std::unique_ptr<ProcessingTimes> processing_times_ = std::make_unique<ProcessingTimes>();
  long iterations_at_last_diagnostic_ = 0;
  ros::WallTime last_diagnostic_time_;
  std::deque<double> nis_window_;  // the last nis_window NIS values
  long drops_at_last_diagnostic_ = 0;
  long laser_pose_changes_ = 0;

  // Rear laser (empty rear_scan_topic: none of this is used).
  struct RearScan {
    Scan scan;
    ros::Time stamp;
    std::string frame_id;
  };
  ros::Subscriber rear_subscriber_;
  std::deque<RearScan> rear_scans_;   // newest last, stamps increasing
  std::optional<Pose2> front_mount_;  // filter.laser_pose of the configuration (else tf)
  long rear_received_ = 0;            // rear messages received
  long rear_refused_ = 0;             // … refused: bad geometry, no frame, stamp
  long merged_scans_ = 0;             // scans processed with a rear scan merged in
  long alone_no_rear_ = 0;            // … alone: no rear scan within rear_scan_tolerance
  long alone_no_transform_ = 0;       // … alone: the rear scan's transforms missing
  long alone_at_last_diagnostic_ = 0;
};

}  // namespace ekf_slam
