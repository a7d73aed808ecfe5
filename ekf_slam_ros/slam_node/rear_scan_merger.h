// The rear laser (~rear_scan_topic): keeps the rear scans received, and
// merges each released scan with the rear scan nearest in time into one
// 360° scan about base_link (ekf_slam_core/sensors/scan_merge.h).
//
// The rear scan used is the one nearest the scan's stamp among those
// received by the time the scan's own transforms are there, within
// rear_scan_tolerance, whose transforms (base_link → its frame, odom →
// base_link at its stamp) exist; the merge moves its readings by the
// odometry between the two stamps. Without one the scan is used alone, in
// the same 360° form (the pipeline's laser pose stays the identity), and
// counted with the reason.
//
// Owns the rear subscriber, the kept rear scans and the counters
// /diagnostics reports.
#pragma once

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include <deque>
#include <optional>
#include <string>

#include "ekf_slam_core/sensors/scan.h"
#include "ekf_slam_ros/slam_node/drop_counter.h"
#include "ekf_slam_ros/slam_node/input_queue.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"
#include "ekf_slam_ros/slam_node/transform_source.h"

namespace ekf_slam {

struct RearCounters {
  long received = 0;            // rear messages received
  long refused = 0;             // … refused: bad geometry, no frame, stamp
  long merged = 0;              // scans processed with a rear scan merged in
  long alone_no_rear = 0;       // … alone: no rear scan within rear_scan_tolerance
  long alone_no_transform = 0;  // … alone: the rear scan's transforms missing
};

class RearScanMerger {
 public:
  // Subscribes to params.rear_scan_topic. `front_mount`: the front laser's
  // mount from the configuration (else tf gives it per scan). `params`,
  // `transforms` and `drops` must outlive the merger.
  RearScanMerger(ros::NodeHandle node, const SlamNodeParams& params,
                 const std::optional<Pose2>& front_mount, const TransformSource& transforms,
                 DropCounter& drops, const std::string& scan_topic);

  // `pending` (a released scan; `odometry` odom → base_link and
  // `front_mount` base_link → its frame at its stamp) merged with the rear
  // scan nearest in time, or alone (counted) when there is none within
  // rear_scan_tolerance or its transforms are missing; framed base_link.
  // Nothing (and a kBadScanGeometry drop) when the scan cannot be placed.
  std::optional<PendingInput> merge(const PendingInput& pending, const Pose2& odometry,
                                    const Pose2& front_mount);
  const RearCounters& counters() const { return counters_; }

 private:
  struct RearScan {
    Scan scan;
    ros::Time stamp;
    std::string frame_id;
  };
  void onRearScan(const sensor_msgs::LaserScan::ConstPtr& message);
  // Why a rear scan is refused (empty: kept); may empty the kept scans.
  std::string refusal(const RearScan& rear, const sensor_msgs::LaserScan& message);
  // The scan merged alone, counted and logged with why.
  void countAlone(const ros::Time& stamp, bool had_candidates, const std::string& missing);

  const SlamNodeParams& params_;
  std::optional<Pose2> front_mount_;  // filter.laser_pose of the configuration (else tf)
  const TransformSource& transforms_;
  DropCounter& drops_;
  ros::Subscriber subscriber_;
  std::deque<RearScan> rear_scans_;  // newest last, stamps increasing
  RearCounters counters_;
};

}  // namespace ekf_slam
