// ekf_slam_node's rear laser (~rear_scan_topic): the rear scans kept for
// merging, and each released scan merged with the rear scan nearest in time
// into one 360° scan about base_link (ekf_slam_core/sensors/scan_merge.h).
//
// The rear scan used is the one nearest the scan's stamp among those
// received by the time the scan's own transforms are there, within
// rear_scan_tolerance, whose transforms (base_link → its frame, odom →
// base_link at its stamp) exist; the merge moves its readings by the
// odometry between the two stamps. Without one the scan is used alone, in
// the same 360° form (the pipeline's laser pose stays the identity), and
// counted on /diagnostics with the reason.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ekf_slam_ros/slam_node/slam_node.h"

namespace ekf_slam {
namespace {

// Rear scans kept at most (about 5 s of an LMS200); older ones are also
// dropped once no scan can use them any more.
constexpr size_t kMaxRearScans = 50;

}  // namespace

void SlamNode::onRearScan(const sensor_msgs::LaserScan::ConstPtr& message) {
  ++rear_received_;
  std::ostringstream problem;
  problem.setf(std::ios::fixed);
  problem.precision(3);
  const ros::Time stamp = message->header.stamp;
  RearScan rear;
  rear.scan = ros_conversions::fromLaserScan(*message);
  rear.stamp = stamp;
  rear.frame_id = message->header.frame_id;
  std::string geometry = ros_conversions::rangeCountError(*message);
  if (geometry.empty()) geometry = validateScan(rear.scan);
  const ros::Time now = ros::Time::now();
  if (!geometry.empty()) {
    problem << geometry;
  } else if (rear.frame_id.empty()) {
    problem << "it has no frame_id";
  } else if (!now.isZero() && (stamp - now).toSec() > params_.max_future_stamp) {
    problem << "its stamp is " << (stamp - now).toSec() << " s ahead of the clock " << now.toSec()
            << " (max_future_stamp " << params_.max_future_stamp << " s)";
  } else if (!rear_scans_.empty() && !(stamp > rear_scans_.back().stamp)) {
    const double back = (rear_scans_.back().stamp - stamp).toSec();
    if (back > 1.0) {
      // The clock went back (a bag restarted): the kept scans are of the
      // old run.
      rear_scans_.clear();
    } else {
      problem << "its stamp is " << back << " s before or equal to the previous rear scan's";
    }
  }
  if (!problem.str().empty()) {
    ++rear_refused_;
    ROS_WARN_THROTTLE(2.0, "ekf_slam_node: rear scan at %.3f on %s refused: %s (%ld so far)",
                      stamp.toSec(), rear_subscriber_.getTopic().c_str(), problem.str().c_str(),
                      rear_refused_);
    return;
  }
  rear_scans_.push_back(std::move(rear));
  while (rear_scans_.size() > kMaxRearScans) rear_scans_.pop_front();
}

void SlamNode::processWithRear(const PendingInput& pending, const Pose2& odometry,
                               const Pose2& front_mount) {
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
    if (!lookup(params_.base_frame, rear->frame_id, rear->stamp, &rear_mount, &why) ||
        !lookup(params_.odom_frame, params_.base_frame, rear->stamp, &rear_odometry, &why)) {
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
    drop(DropReason::kBadScanGeometry, "scan at " + std::to_string(stamp.toSec()) +
                                           " cannot be placed about " + params_.base_frame + ": " +
                                           error + "; the map is not touched");
    return;
  }

  if (second.scan != &none) {
    ++merged_scans_;
  } else if (!candidates.empty()) {
    // Logged per reason, so that one does not hide the other.
    ++alone_no_transform_;
    ROS_WARN_THROTTLE(2.0,
                      "ekf_slam_node: scan at %.3f used without the rear laser: the transforms "
                      "of its rear scan are missing: %s",
                      stamp.toSec(), missing.c_str());
  } else {
    ++alone_no_rear_;
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
                      stamp.toSec(), rear_subscriber_.getTopic().c_str(),
                      params_.rear_scan_tolerance, nearest.str().c_str());
  }
  // Scans come in stamp order: a rear scan older than this one's window
  // can serve no later scan.
  while (!rear_scans_.empty() &&
         (stamp - rear_scans_.front().stamp).toSec() > params_.rear_scan_tolerance) {
    rear_scans_.pop_front();
  }
  merged.header.frame_id = params_.base_frame;
  process(merged, odometry, Pose2());
}

}  // namespace ekf_slam
