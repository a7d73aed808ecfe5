#include "ekf_slam_core/pipeline/scan_history.h"

#include <algorithm>

namespace ekf_slam {

KeptScan::KeptScan(long scan_number, const Scan& readings, const Pose2& causal_pose)
    : scan(scan_number),
      ranges(readings.ranges.begin(), readings.ranges.end()),
      angle_min(readings.angle_min),
      angle_increment(readings.angle_increment),
      range_min(readings.range_min),
      range_max(readings.range_max),
      stamp(readings.stamp),
      causal(causal_pose) {}

Scan KeptScan::toScan() const {
  Scan out;
  out.ranges.assign(ranges.begin(), ranges.end());
  out.angle_min = angle_min;
  out.angle_increment = angle_increment;
  out.range_min = range_min;
  out.range_max = range_max;
  out.stamp = stamp;
  return out;
}

ScanHistory::ScanHistory(long bound, const Pose2& prior, const Matrix3& prior_covariance,
                         const KeptReadingsOptions& readings)
    : bound_(bound), readings_(readings) {
  full_recorder_.setPrior(prior, prior_covariance);
}

void ScanHistory::addIteration(double stamp, const EkfSlam& filter, const OdometryControl* control,
                               const std::vector<PointObservation>& observations,
                               const IterationReport& report, const Pose2* local_motion,
                               const Pose2* wheels) {
  recorder_.addFiltered(stamp, filter.pose(), filter.poseCovariance());
  full_recorder_.addIteration(stamp, filter, control, observations, report, local_motion, wheels);
}

// The history beyond the bound goes an eighth of the bound at a time (one
// erase per many scans instead of one per scan).
long ScanHistory::add(const ScanRecord& record, const Scan* scan) {
  if (readings_.keep && scan != nullptr) {
    kept_.emplace_back(recordedScans(), *scan, record.causal);
    if (bound_ > 0 && static_cast<long>(kept_.size()) > bound_) {
      if (!left_grid_) left_grid_.emplace(readings_.grid);
      const KeptScan& oldest = kept_.front();
      left_grid_->insertScan(compose(oldest.causal, readings_.laser_pose), oldest.toScan());
      kept_.pop_front();
    }
  }
  records_.push_back(record);
  const long keep = bound_;
  if (keep <= 0) return 0;
  const long slack = std::max(1L, keep / 8);
  if (static_cast<long>(records_.size()) < keep + slack) return 0;
  const long drop = static_cast<long>(records_.size()) - keep;
  records_.erase(records_.begin(), records_.begin() + drop);
  first_record_ += drop;
  // The iterations before the one the oldest kept scan hangs off; the first
  // kept one becomes the smoother's start, with the filter's estimate there.
  const int gone = records_.front().iteration - first_iteration_;
  if (gone > 0 && gone < static_cast<int>(recorder_.steps().size())) {
    const SmootherStep& start = recorder_.steps()[gone];
    full_recorder_.setPrior(start.filtered, start.filtered_cov);
    recorder_.dropFront(gone);
    full_recorder_.dropFront(gone);
    first_iteration_ += gone;
  }
  return drop;
}

const KeptScan* ScanHistory::keptScan(long scan) const {
  const auto at = std::lower_bound(kept_.begin(), kept_.end(), scan,
                                   [](const KeptScan& kept, long n) { return kept.scan < n; });
  return at != kept_.end() && at->scan == scan ? &*at : nullptr;
}

const ScanRecord* ScanHistory::record(long scan) const {
  const long r = scan - first_record_;
  if (r < 0 || r >= static_cast<long>(records_.size())) return nullptr;
  return &records_[r];
}

std::vector<StampedPose> ScanHistory::scanPosesFrom(
    const std::vector<Pose2>& iteration_poses) const {
  std::vector<StampedPose> out;
  out.reserve(records_.size());
  for (const ScanRecord& r : records_) {
    const int k = r.iteration - first_iteration_;
    if (r.iteration < 0 || k < 0 || k >= static_cast<int>(iteration_poses.size())) {
      out.push_back({r.stamp, r.filtered});
      continue;
    }
    out.push_back(
        {r.stamp, compose(iteration_poses[k], between(r.odometry_at_iteration, r.odometry))});
  }
  return out;
}

std::vector<StampedPose> ScanHistory::filteredScanPoses() const {
  std::vector<StampedPose> out;
  out.reserve(records_.size());
  for (const ScanRecord& r : records_) out.push_back({r.stamp, r.filtered});
  return out;
}

std::vector<StampedPose> ScanHistory::causalScanPoses() const {
  std::vector<StampedPose> out;
  out.reserve(records_.size());
  for (const ScanRecord& r : records_) out.push_back({r.stamp, r.causal});
  return out;
}

std::vector<StampedPose> ScanHistory::rtsScanPoses() const {
  std::vector<Pose2> poses;
  for (const SmoothedPose& p : smoothTrajectory(recorder_.steps())) poses.push_back(p.pose);
  return scanPosesFrom(poses);
}

}  // namespace ekf_slam
