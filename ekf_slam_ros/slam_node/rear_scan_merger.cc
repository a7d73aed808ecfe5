#include "ekf_slam_ros/slam_node/rear_scan_merger.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ekf_slam_core/sensors/scan_merge.h"
#include "ekf_slam_ros/conversions/scan_conversion.h"

namespace ekf_slam {
namespace {

// Rear scans kept at most (about 5 s of an LMS200); older ones are also
// dropped once no scan can use them any more.
constexpr size_t kMaxRearScans = 50;

}  // namespace

RearScanMerger::RearScanMerger(ros::NodeHandle node, const SlamNodeParams& params,
                               const std::optional<Pose2>& front_mount,
                               const TransformSource& transforms, DropCounter& drops,
                               const std::string& scan_topic)
    : params_(params), front_mount_(front_mount), transforms_(transforms), drops_(drops) {
  subscriber_ = node.subscribe(params_.rear_scan_topic, 50, &RearScanMerger::onRearScan, this);
  ROS_INFO("ekf_slam_node: merging %s with the rear laser's %s (tolerance %.3f s)",
           scan_topic.c_str(), subscriber_.getTopic().c_str(), params_.rear_scan_tolerance);
}

std::string RearScanMerger::refusal(const RearScan& rear, const sensor_msgs::LaserScan& message) {
  std::ostringstream problem;
  problem.setf(std::ios::fixed);
  problem.precision(3);
  std::string geometry = ros_conversions::rangeCountError(message);
  if (geometry.empty()) geometry = validateScan(rear.scan);
  const ros::Time reached = transforms_.dataTime(params_.odom_frame, params_.base_frame);
  const double tolerance = transforms_.futureTolerance();
  if (!geometry.empty()) {
    problem << geometry;
  } else if (rear.frame_id.empty()) {
    problem << "it has no frame_id";
  } else if (!reached.isZero() && (rear.stamp - reached).toSec() > tolerance) {
    problem << "its stamp is " << (rear.stamp - reached).toSec()
            << " s ahead of the clock and the odometry (" << reached.toSec()
            << "; max_future_stamp × the clock's rate: " << tolerance << " s)";
  } else if (!rear_scans_.empty() && !(rear.stamp > rear_scans_.back().stamp)) {
    const double back = (rear_scans_.back().stamp - rear.stamp).toSec();
    if (back > 1.0) {
      // The clock went back (a bag restarted): the kept scans are of the
      // old run.
      rear_scans_.clear();
    } else {
      problem << "its stamp is " << back << " s before or equal to the previous rear scan's";
    }
  }
  return problem.str();
}

void RearScanMerger::onRearScan(const sensor_msgs::LaserScan::ConstPtr& message) {
  ++counters_.received;
  RearScan rear;
  rear.scan = ros_conversions::fromLaserScan(*message);
  rear.stamp = message->header.stamp;
  rear.frame_id = message->header.frame_id;
  const std::string problem = refusal(rear, *message);
  if (!problem.empty()) {
    ++counters_.refused;
    ROS_WARN_THROTTLE(2.0, "ekf_slam_node: rear scan at %.3f on %s refused: %s (%ld so far)",
                      rear.stamp.toSec(), subscriber_.getTopic().c_str(), problem.c_str(),
                      counters_.refused);
    return;
  }
  rear_scans_.push_back(std::move(rear));
  while (rear_scans_.size() > kMaxRearScans) rear_scans_.pop_front();
}

std::optional<PendingInput> RearScanMerger::merge(const PendingInput& pending,
                                                  const Pose2& odometry, const Pose2& front_mount) {
  const ros::Time stamp = pending.header.stamp;
  const Scan& front = *pending.scan;

  // The rear scans within the tolerance, nearest first.
  std::vector<const RearScan*> candidates;
  for (const RearScan& rear : rear_scans_) {
    if (std::abs((rear.stamp - stamp).toSec()) <= params_.rear_scan_tolerance) {
      candidates.push_back(&rear);
    }
  }
  std::stable_sort(
      candidates.begin(), candidates.end(), [&stamp](const RearScan* a, const RearScan* b) {
        return std::abs((a->stamp - stamp).toSec()) < std::abs((b->stamp - stamp).toSec());
      });
  const Scan none;
  MountedScan second{&none, Pose2()};
  Pose2 motion;
  std::string missing;
  for (const RearScan* rear : candidates) {
    Pose2 rear_mount, rear_odometry;
    std::string why;
    if (!transforms_.lookup(params_.base_frame, rear->frame_id, rear->stamp, &rear_mount, &why) ||
        !transforms_.lookup(params_.odom_frame, params_.base_frame, rear->stamp, &rear_odometry,
                            &why)) {
      if (missing.empty()) missing = why;
      continue;
    }
    second = {&rear->scan, rear_mount};
    motion = between(odometry, rear_odometry);
    break;
  }

  ScanMergeOptions options;
  options.angle_increment = params_.merged_angle_increment > 0.0
                                ? params_.merged_angle_increment
                                : std::clamp(std::abs(front.angle_increment), 1e-4, kPi / 4.0);
  const MountedScan first{&front, front_mount_ ? *front_mount_ : front_mount};
  PendingInput merged = pending;
  merged.scan.emplace();
  std::string error = mergeScans(first, second, motion, options, &*merged.scan);
  if (!error.empty() && second.scan != &none) {
    // Not expected (both scans were checked on arrival); the scan alone.
    missing = "merging failed: " + error;
    second = {&none, Pose2()};
    error = mergeScans(first, second, Pose2(), options, &*merged.scan);
  }
  if (!error.empty()) {
    drops_.drop(DropReason::kBadScanGeometry, "scan at " + std::to_string(stamp.toSec()) +
                                                  " cannot be placed about " + params_.base_frame +
                                                  ": " + error + "; the map is not touched");
    return std::nullopt;
  }
  if (second.scan != &none) {
    ++counters_.merged;
  } else {
    countAlone(stamp, !candidates.empty(), missing);
  }
  // Scans come in stamp order: a rear scan older than this one's window
  // can serve no later scan.
  while (!rear_scans_.empty() &&
         (stamp - rear_scans_.front().stamp).toSec() > params_.rear_scan_tolerance) {
    rear_scans_.pop_front();
  }
  merged.header.frame_id = params_.base_frame;
  return merged;
}

void RearScanMerger::countAlone(const ros::Time& stamp, bool had_candidates,
                                const std::string& missing) {
  if (had_candidates) {
    // Logged per reason, so that one does not hide the other.
    ++counters_.alone_no_transform;
    ROS_WARN_THROTTLE(2.0,
                      "ekf_slam_node: scan at %.3f used without the rear laser: the transforms "
                      "of its rear scan are missing: %s",
                      stamp.toSec(), missing.c_str());
    return;
  }
  ++counters_.alone_no_rear;
  std::ostringstream nearest;
  nearest.setf(std::ios::fixed);
  nearest.precision(3);
  double gap = -1.0;
  for (const RearScan& rear : rear_scans_) {
    const double g = std::abs((rear.stamp - stamp).toSec());
    if (gap < 0.0 || g < gap) gap = g;
  }
  if (gap >= 0.0) nearest << " (the nearest is " << gap << " s away)";
  ROS_WARN_THROTTLE(2.0,
                    "ekf_slam_node: scan at %.3f used without the rear laser: no rear scan on "
                    "%s within rear_scan_tolerance %.3f s%s",
                    stamp.toSec(), subscriber_.getTopic().c_str(), params_.rear_scan_tolerance,
                    nearest.str().c_str());
}

}  // namespace ekf_slam
