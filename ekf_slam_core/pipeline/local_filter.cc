#include "ekf_slam_core/pipeline/local_filter.h"

#include <algorithm>

namespace ekf_slam {

namespace {
std::optional<LineLandmarks> lineLandmarksFor(const PipelineOptions& options) {
  switch (options.landmarks) {
    case LandmarkSet::kPoints:
    case LandmarkSet::kPointsAndMecp:
      return std::nullopt;
    case LandmarkSet::kPointsAndLines:
      return LineLandmarks(LandmarkKind::kLine, options.lines, options.association);
    case LandmarkSet::kPointsAndLineAngles:
      return LineLandmarks(LandmarkKind::kLineAngle, options.lines, options.association);
  }
  return std::nullopt;
}

// With scan matching the control is the scan-matched increment, with its
// own noise.
FilterOptions filterOptionsFor(const PipelineOptions& options) {
  FilterOptions filter = options.filter;
  if (options.scan_matching.enabled) filter.motion_noise = options.scan_matched_motion_noise;
  return filter;
}
}  // namespace

LocalFilter::LocalFilter(const PipelineOptions& options)
    : options_(options),
      filter_(filterOptionsFor(options), options.initial_pose, options.initial_pose_covariance),
      lines_(lineLandmarksFor(options)) {
  if (options.landmarks == LandmarkSet::kPointsAndMecp) mecp_.emplace();
  if (options.rooms.enabled) rooms_.emplace(options.rooms);
}

Pose2 LocalFilter::deadReckoned(const Pose2& anchor, const Pose2& odometry) const {
  return compose(filter_.pose(), between(anchor, odometry));
}

Matrix3 LocalFilter::deadReckonedCovariance(const Pose2& anchor, const Pose2& odometry) const {
  const OdometryControl u = controlFromOdometry(anchor, odometry);
  Matrix3 F, G;
  applyControl(filter_.pose(), u, &F, &G);
  const Matrix3 covariance =
      F * filter_.poseCovariance() * F.transpose() +
      G * controlCovariance(u, filter_.options().motion_noise) * G.transpose();
  return 0.5 * (covariance + covariance.transpose());
}

void LocalFilter::update(ScanResult* out) {
  const std::vector<PointFeature>& points = out->features.points_of_interest;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    const PointFeature& point = points[i];
    if (!point.landmark_candidate || point.range > options_.max_landmark_range ||
        point.range < options_.min_landmark_range) {
      continue;
    }
    PointObservation obs;
    obs.z = {point.range, point.bearing};
    obs.covariance = point.range_bearing_covariance;
    out->observations.push_back(obs);
    out->observation_feature.push_back(i);
  }
  out->iteration.predict_status = FilterStatus::kOk;
  Associator associator = rooms_ ? rooms_->associator() : nullptr;
  if (mecp_) {
    associator = [this, base = std::move(associator)](
                     const EkfSlam& filter, const std::vector<PointObservation>& observations,
                     const AssociationOptions& association) {
      return mecp_->associate(filter, observations, association, base);
    };
  }
  observe(filter_, options_.association, out->observations, &out->iteration, associator);
  if (mecp_) mecp_->remember(filter_, out->iteration);
  if (rooms_) {
    const Vector2 laser = compose(filter_.pose(), options_.filter.laser_pose).translation();
    rooms_->labelNew(filter_, out->iteration, laser);
  }
  if (lines_) {
    lines_->observe(filter_, out->features, out->observation_feature, out->iteration, &out->lines);
  }
}

void LocalFilter::maintain(const ScanResult& result) {
  const IterationReport& iteration = result.iteration;
  if (iteration.update_status != FilterStatus::kOk) ++points_.update_failures;
  points_.observations += static_cast<long>(result.observations.size());
  points_.matches += static_cast<long>(iteration.matches.size());
  points_.pruned += iteration.pruned;
  points_.pruned_rare += pruneRarelySeen();
  points_.marginalised += boundLandmarks();
  if (lines_) {
    lines_->synchronise(filter_);
    const LineIterationReport& lines = result.lines;
    lines_counted_.line_observations += static_cast<long>(lines.observations.size());
    lines_counted_.line_matches += static_cast<long>(lines.matches.size());
    lines_counted_.line_endpoint_matches += lines.endpoint_matches;
    lines_counted_.line_ambiguous += lines.ambiguous;
    lines_counted_.new_line_landmarks += static_cast<long>(lines.new_landmark_ids.size());
    lines_counted_.lines_refused += lines.refused;
    if (lines.update_status != FilterStatus::kOk) ++lines_counted_.line_update_failures;
    for (double nis : lines.nis) lines_counted_.line_nis_sum += nis;
  }
  for (const ObservationAssociation& a : iteration.association.observations) {
    if (a.decision == AssociationDecision::kAmbiguous) ++points_.ambiguous;
  }
  points_.new_landmarks += static_cast<long>(iteration.new_landmark_ids.size());
  for (double nis : iteration.nis) points_.nis_sum += nis;
  // Room gating needs walls: validate() refuses it without line landmarks.
  if (rooms_) rooms_->afterIteration(filter_, *lines_);
}

void LocalFilter::reanchor(const Pose2& robot_correction,
                           const std::vector<std::pair<int, Pose2>>& corrections) {
  filter_.reanchor(robot_correction, corrections);
  if (lines_) {
    lines_->reanchor(corrections);
    lines_->synchronise(filter_);
  }
  ++points_.reanchors;
}

// Map management: a landmark matched fewer than prune_min_observations
// times (its creation included) once prune_age_steps iterations old is
// removed.
int LocalFilter::pruneRarelySeen() {
  if (options_.prune_min_observations <= 0) return 0;
  std::vector<int> ids;
  for (const LandmarkInfo& info : filter_.landmarks()) {
    if (info.observations < options_.prune_min_observations &&
        filter_.step() - info.created_step >= options_.prune_age_steps) {
      ids.push_back(info.id);
    }
  }
  for (int id : ids) filter_.removeLandmark(id);
  return static_cast<int>(ids.size());
}

int LocalFilter::boundLandmarks() {
  const int excess = filter_.landmarkCount() - options_.max_landmarks;
  if (options_.max_landmarks <= 0 || excess <= 0) return 0;
  // Least recently matched first; of those, the oldest.
  std::vector<const LandmarkInfo*> order;
  order.reserve(filter_.landmarks().size());
  for (const LandmarkInfo& info : filter_.landmarks()) order.push_back(&info);
  std::partial_sort(order.begin(), order.begin() + excess, order.end(),
                    [](const LandmarkInfo* a, const LandmarkInfo* b) {
                      if (a->last_seen_step != b->last_seen_step)
                        return a->last_seen_step < b->last_seen_step;
                      return a->id < b->id;
                    });
  std::vector<int> ids;
  ids.reserve(excess);
  for (int i = 0; i < excess; ++i) ids.push_back(order[i]->id);
  return filter_.removeLandmarks(ids);
}

const std::unordered_map<int, LineSupport>& LocalFilter::lineSupport() const {
  static const std::unordered_map<int, LineSupport> kNone;
  return lines_ ? lines_->support() : kNone;
}

void LocalFilter::seedLineSupport(const std::unordered_map<int, LineSupport>& support) {
  if (lines_) lines_->seed(filter_, support);
}

FilterCounters LocalFilter::counters() const {
  FilterCounters out;
  static_cast<PointCounters&>(out) = points_;
  static_cast<LineCounters&>(out) = lines_counted_;
  if (mecp_) static_cast<MecpCounters&>(out) = mecp_->counters();
  if (rooms_) static_cast<RoomCounters&>(out) = rooms_->counters();
  return out;
}

}  // namespace ekf_slam
