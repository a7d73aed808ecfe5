#include "ekf_slam_core/pipeline/scan_history.h"

#include <algorithm>
#include <unordered_map>

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

ScanHistoryState ScanHistory::state() const {
  ScanHistoryState out;
  out.records = records_;
  out.first_record = first_record_;
  out.first_iteration = first_iteration_;
  out.steps = recorder_.steps();
  out.iterations = full_recorder_.iterations();
  const auto& merged = full_recorder_.mergedInto();
  out.merged_into.assign(merged.begin(), merged.end());
  std::sort(out.merged_into.begin(), out.merged_into.end());
  const auto& estimates = full_recorder_.lastEstimates();
  out.last_estimates.assign(estimates.begin(), estimates.end());
  std::sort(out.last_estimates.begin(), out.last_estimates.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  out.prior_mean = full_recorder_.priorMean();
  out.prior_covariance = full_recorder_.priorCovariance();
  return out;
}

void keepNewestScans(long max_scans, ScanHistoryState* state) {
  const long drop = static_cast<long>(state->records.size()) - max_scans;
  if (max_scans <= 0 || drop <= 0) return;
  state->records.erase(state->records.begin(), state->records.begin() + drop);
  state->first_record += drop;
  const int gone = state->records.front().iteration - state->first_iteration;
  if (gone <= 0 || gone >= static_cast<int>(state->steps.size())) return;
  // The recorder's own trimming keeps what the remaining sightings need.
  FullSmootherRecorder recorder;
  recorder.restore(
      std::move(state->iterations),
      std::unordered_map<int, int>(state->merged_into.begin(), state->merged_into.end()),
      std::unordered_map<int, Vector2>(state->last_estimates.begin(), state->last_estimates.end()),
      state->steps[gone].filtered, state->steps[gone].filtered_cov);
  recorder.dropFront(gone);
  state->steps.erase(state->steps.begin(), state->steps.begin() + gone);
  state->first_iteration += gone;
  state->iterations = recorder.iterations();
  state->merged_into.assign(recorder.mergedInto().begin(), recorder.mergedInto().end());
  std::sort(state->merged_into.begin(), state->merged_into.end());
  state->last_estimates.assign(recorder.lastEstimates().begin(), recorder.lastEstimates().end());
  std::sort(state->last_estimates.begin(), state->last_estimates.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  state->prior_mean = recorder.priorMean();
  state->prior_covariance = recorder.priorCovariance();
}

std::string ScanHistory::restore(const ScanHistoryState& state) {
  if (state.steps.size() != state.iterations.size()) {
    return "the history's two records of the iterations differ in length";
  }
  if (state.first_record < 0 || state.first_iteration < 0) {
    return "the history starts at a negative scan or iteration";
  }
  const int iterations = static_cast<int>(state.iterations.size());
  int last = -1;
  for (const ScanRecord& r : state.records) {
    // A scan hangs off an iteration at or after the history's first
    // (-1: a scan before the first iteration), never off a later one.
    if (r.iteration < last || r.iteration >= state.first_iteration + iterations ||
        (r.iteration >= 0 && r.iteration < state.first_iteration && iterations > 0)) {
      return "a scan of the history hangs off an iteration it does not hold";
    }
    last = r.iteration;
  }
  records_ = state.records;
  first_record_ = state.first_record;
  first_iteration_ = state.first_iteration;
  recorder_.restore(state.steps);
  full_recorder_.restore(
      state.iterations,
      std::unordered_map<int, int>(state.merged_into.begin(), state.merged_into.end()),
      std::unordered_map<int, Vector2>(state.last_estimates.begin(), state.last_estimates.end()),
      state.prior_mean, state.prior_covariance);
  kept_.clear();
  left_grid_.reset();
  return "";
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
