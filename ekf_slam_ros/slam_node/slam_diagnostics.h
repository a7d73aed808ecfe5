// ekf_slam_node's /diagnostics ("EKF-SLAM"): the inputs and their drops by
// reason, the filter's health (NIS against its 95 % band, scan matching),
// the back end, the rear laser, the live map and the processing times.
// Every part it reports on is handed to it at construction, read-only.
//
// Owns the updater and its timer, the NIS window, the processing times,
// and what the summary compares with the last report.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <chrono>
#include <deque>
#include <memory>

#include "ekf_slam_core/pipeline/scan_result.h"
#include "ekf_slam_ros/offline/slam_config.h"
#include "ekf_slam_ros/slam_node/drop_counter.h"
#include "ekf_slam_ros/slam_node/grid_output.h"
#include "ekf_slam_ros/slam_node/input_queue.h"
#include "ekf_slam_ros/slam_node/processing_times.h"
#include "ekf_slam_ros/slam_node/rear_scan_merger.h"
#include "ekf_slam_ros/slam_node/relocaliser.h"
#include "ekf_slam_ros/slam_node/slam_control.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"
#include "ekf_slam_ros/slam_node/slam_services.h"
#include "ekf_slam_ros/slam_node/transform_source.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {

class SlamDiagnostics {
 public:
  // What the report reads; each must outlive the diagnostics.
  struct Sources {
    const SlamControl* slam = nullptr;
    const DropCounter* drops = nullptr;
    const TransformSource* transforms = nullptr;
    const InputQueue* input = nullptr;
    const RearScanMerger* rear = nullptr;  // null without a rear laser
    const GridOutput* grids = nullptr;
    const SlamServices* services = nullptr;
    const Relocaliser* relocaliser = nullptr;
  };

  SlamDiagnostics(ros::NodeHandle node, ros::NodeHandle private_node, const SlamNodeParams& params,
                  const PipelineOptions& pipeline, const Sources& sources);

  // Times its own lifetime as one input's processing (pipeline and
  // publication; not the tf wait before it).
  class Timing {
   public:
    explicit Timing(ProcessingTimes* times)
        : times_(times), start_(std::chrono::steady_clock::now()) {}
    ~Timing();
    Timing(const Timing&) = delete;
    Timing& operator=(const Timing&) = delete;

   private:
    ProcessingTimes* times_;
    std::chrono::steady_clock::time_point start_;
  };
  Timing timeProcessing() { return Timing(processing_times_.get()); }
  // An iteration's NIS values, into the window.
  void addIteration(const ScanResult& result);
  void countLaserPoseChange() { ++laser_pose_changes_; }
  // The mount of the laser (`frame`) at the last input processed.
  void noteLaserMount(const std::string& frame, const ros_conversions::LaserMount& mount) {
    laser_frame_ = frame;
    laser_mount_ = mount;
  }
  // A new pipeline: the NIS window and the iteration rate start again.
  void restart();

 private:
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  // The parts of the report, in the order it lists them.
  void addScanMatching(const PipelineCounters& counters,
                       diagnostic_updater::DiagnosticStatusWrapper& status) const;
  void addBackEnd(const PipelineCounters& counters,
                  diagnostic_updater::DiagnosticStatusWrapper& status) const;
  void addRearAndMap(diagnostic_updater::DiagnosticStatusWrapper& status) const;
  void summarise(long drops, long alone, bool nis_inside,
                 diagnostic_updater::DiagnosticStatusWrapper& status) const;
  void addCounts(const PipelineCounters& counters, long iterations, double rate,
                 diagnostic_updater::DiagnosticStatusWrapper& status) const;
  double nisAverage() const;  // over the window; 0 when it is empty
  // The NIS band; false when the average lies outside it.
  bool addNisBand(diagnostic_updater::DiagnosticStatusWrapper& status) const;

  const SlamNodeParams& params_;
  const bool loop_closure_;
  const bool mecp_;
  Sources sources_;
  diagnostic_updater::Updater updater_;
  ros::WallTimer timer_;
  ros::WallTime last_published_;
  std::deque<double> nis_window_;  // the last nis_window NIS values
  // Wall time of each input's processing, over the whole run.
  std::unique_ptr<ProcessingTimes> processing_times_ = std::make_unique<ProcessingTimes>();
  long iterations_at_last_ = 0;
  ros::WallTime last_time_;
  long drops_at_last_ = 0;
  long alone_at_last_ = 0;
  long laser_pose_changes_ = 0;
  std::string laser_frame_;  // empty before the first input
  ros_conversions::LaserMount laser_mount_;
};

}  // namespace ekf_slam
