#include "ekf_slam_core/pipeline/front_end.h"

namespace ekf_slam {

namespace {
// The full smoother's local matcher, when its motion edges need one.
std::optional<ScanMatchingOdometry> localMatcherFor(const PipelineOptions& options) {
  if (!options.scan_matching.enabled || options.scan_matching.map_mode != "global" ||
      options.smoother.motion_edges != SmootherMotion::kLocalMatch) {
    return std::nullopt;
  }
  ScanMatcherOptions local = options.scan_matching;
  local.map_mode = "local";
  local.local_map_scans = options.smoother.local_match_key_scans;
  return ScanMatchingOdometry(local, options.filter.motion_noise);
}
}  // namespace

FrontEnd::FrontEnd(const PipelineOptions& options)
    : laser_pose_(options.filter.laser_pose),
      matching_(options.scan_matching),
      max_step_translation_(options.filter.max_step_translation),
      max_step_rotation_(options.filter.max_step_rotation),
      local_matcher_(localMatcherFor(options)) {
  if (options.scan_matching.enabled) {
    scan_matcher_.emplace(options.scan_matching, options.filter.motion_noise);
  }
  counters_.local_matcher_runs = local_matcher_.has_value();
}

Pose2 FrontEnd::track(const Scan* scan, const Pose2& raw_odometry, bool usable, bool check_jump,
                      bool* jumped) {
  *jumped = false;
  if (!scan_matcher_) return raw_odometry;
  if (!usable) {
    if (local_matcher_) local_pose_ = local_matcher_->deadReckon(raw_odometry);
    return scan_matcher_->deadReckon(raw_odometry);
  }
  if (check_jump &&
      scan_matcher_->isOdometryJump(raw_odometry, max_step_translation_, max_step_rotation_)) {
    scan_matcher_->reanchorRaw(raw_odometry);
    if (local_matcher_) local_matcher_->reanchorRaw(raw_odometry);
    *jumped = true;
  }
  // Both matchers take the scan's points with the same options
  // (localMatcherFor changes only the map's).
  const std::vector<Vector2> points = scanPointsInRobotFrame(*scan, laser_pose_, matching_);
  if (local_matcher_) {
    local_pose_ = local_matcher_->processPoints(points, scan->stamp, raw_odometry);
  }
  MatchResult match;
  const Pose2 matched = scan_matcher_->processPoints(points, scan->stamp, raw_odometry, &match);
  counters_.front_end = scan_matcher_->counters();
  if (local_matcher_) counters_.local_matcher = local_matcher_->counters();
  if (match.ok) {
    ++counters_.scan_matches;
  } else {
    ++counters_.scan_match_refusals;
  }
  return matched;
}

std::optional<Pose2> FrontEnd::localMotion() const {
  if (!local_matcher_ || local_motion_unknown_) return std::nullopt;
  return between(last_local_pose_, local_pose_);
}

}  // namespace ekf_slam
