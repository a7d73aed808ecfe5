// ekf_slam_node: the live EKF-SLAM node, a thin shell around SlamPipeline
// (the same object the offline runner uses, so a bag gives the same answer
// live and offline).
//
// Data flow per scan (all callbacks on one thread, ros::spin, which owns
// the SLAM state; tf arrives through GuardedTfListener's thread, which
// refuses future stamps; the slow services run on their own, see
// slam_services.h):
//   scan → InputQueue: checks, the wait for odom → laser in a
//          tf2_ros::MessageFilter, drops counted by reason (DropCounter)
//        → [RearScanMerger: merged with the rear scan nearest in time]
//        → SlamNode::process: SlamPipeline::processScan(scan, odometry)
//        → MapToOdomBroadcaster (tf map → odom), then ScanOutputs (loop-closed
//          path, pose, paths, landmarks, landmark_map, association).
// With input: features the node takes ekf_slam/Features (feature_node's
// output, stamped and framed as the scan) instead, through the same queue
// into SlamPipeline::processFeatures and the same outputs.
// Beside the scans: GridOutput (the occupancy grid on `map`), SlamServices
// (~pause, ~resume, ~step, ~reset, ~smooth, ~save_map, ~load_map,
// /initialpose), Relocaliser (localising in a loaded state: lost, then
// found again by a global search) and SlamDiagnostics (/diagnostics).
// Nothing is written back into the robot (thesis §3.4.2): the map frame
// is a separate estimate published as map → odom (REP-105).
// Every output is stamped with the scan's stamp (data time), so bag replay
// with use_sim_time gives the same stamps as the live run.
// Topics, services and parameters: docs/live_system.md.
//
// SlamNode owns the pipeline and what starts it (the laser pose, a map to
// seed it with, a start pose), composes the parts above, and is the
// SlamControl through which they see and restart the SLAM state.
#pragma once

#include <ros/ros.h>

#include <memory>
#include <optional>
#include <string>

#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_ros/offline/slam_config.h"
#include "ekf_slam_ros/slam_node/drop_counter.h"
#include "ekf_slam_ros/slam_node/grid_output.h"
#include "ekf_slam_ros/slam_node/input_queue.h"
#include "ekf_slam_ros/slam_node/map_to_odom.h"
#include "ekf_slam_ros/slam_node/rear_scan_merger.h"
#include "ekf_slam_ros/slam_node/relocaliser.h"
#include "ekf_slam_ros/slam_node/scan_outputs.h"
#include "ekf_slam_ros/slam_node/slam_control.h"
#include "ekf_slam_ros/slam_node/slam_diagnostics.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"
#include "ekf_slam_ros/slam_node/slam_services.h"
#include "ekf_slam_ros/slam_node/transform_source.h"

namespace ekf_slam {

class SlamNode : public SlamControl {
 public:
  // Parameters and configuration must be valid (loaded by their loaders).
  SlamNode(ros::NodeHandle node, ros::NodeHandle private_node, const SlamNodeParams& params,
           const SlamConfig& config);
  SlamNode(const SlamNode&) = delete;
  SlamNode& operator=(const SlamNode&) = delete;

  // SlamControl.
  const SlamPipeline* pipeline() const override { return pipeline_.get(); }
  void acceptNextMotion() override;
  ros::Time lastScanStamp() const override { return last_scan_stamp_; }
  long generation() const override { return generation_; }
  bool localizeOnly() const override { return localize_only_; }
  std::optional<LandmarkMapFile> landmarks() const override;
  void dropWaitingInputs() override { input_.clear(); }
  void clearMap() override;
  std::string restart(const Pose2& pose, const Matrix3& covariance,
                      std::optional<LandmarkMapFile> prior, bool localize_only) override;
  std::optional<SlamState> state() const override;
  std::string resumeFrom(SlamState state, bool localize_only) override;

 private:
  // A released input (`odometry` odom → base_link, `laser` base_link → its
  // frame at its stamp): merged with the rear scan first when there is a
  // rear laser, then processed.
  void onReleased(const PendingInput& pending, const Pose2& odometry, const Pose2& laser);
  // One input through the pipeline, then its outputs.
  void process(const PendingInput& pending, const Pose2& odometry, const Pose2& laser);
  // The pipeline at the first input (the laser pose from the configuration
  // or tf); later, a warning when tf's laser pose moved.
  void ensurePipeline(const PendingInput& pending, const Pose2& laser);
  void createPipeline(const Pose2& laser_pose);
  // The options of a live pipeline with the laser at `laser_pose`.
  PipelineOptions liveOptions(const Pose2& laser_pose) const;
  // The pose (map frame) and covariance the next pipeline starts at; empty
  // when the pose and covariance are unusable, else the problem.
  std::string setStartPose(const Pose2& pose, const Matrix3& covariance);
  // A state just resumed: watched for a lost robot when localising in it
  // (relocalise_when_lost), else nothing is.
  void watchForLoss(SlamState state);
  // The robot, lost in the loaded state, was found at `place`: the SLAM
  // state moved there (placeRobot), on a pipeline resumed from it.
  void relocate(const GlobalPlacement& place);
  // The clock jumped back: a new map, or the map kept as the prior of a
  // restarted filter (params.clock_jump).
  void onClockJump();
  // No pipeline; every part forgets what it kept of the last one.
  void resetState();

  SlamNodeParams params_;
  SlamConfig config_;
  TransformSource transforms_;
  DropCounter drops_;

  // SLAM state. The pipeline is created at the first scan, when the laser
  // pose is known (from the configuration or tf).
  std::unique_ptr<SlamPipeline> pipeline_;
  std::optional<Pose2> laser_pose_;             // base_link → laser the pipeline uses
  std::optional<LandmarkMapFile> seed_map_;     // a loaded map waiting for the pipeline
  std::optional<SlamState> seed_state_;         // a loaded state waiting for the pipeline
  std::optional<Pose2> start_pose_;             // where that pipeline starts (map frame) …
  Matrix3 start_covariance_ = Matrix3::Zero();  // … and how sure that is
  bool localize_only_ = false;
  ros::Time last_scan_stamp_;  // of the last processed scan
  long generation_ = 0;        // restarts of the map (SlamControl::generation)

  // The parts, in the order they are built (each may use those before it).
  ScanOutputs outputs_;
  MapToOdomBroadcaster map_to_odom_;
  GridOutput grids_;
  SlamServices services_;
  InputQueue input_;
  std::unique_ptr<RearScanMerger> rear_;  // null without ~rear_scan_topic
  Relocaliser relocaliser_;               // watches a state loaded for localisation
  SlamDiagnostics diagnostics_;
};

}  // namespace ekf_slam
