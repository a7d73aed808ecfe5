// The pipeline's first stage: the control source of the filter. Without
// scan matching it is the robot's raw odometry (the thesis's mode). With
// scan_matching.enabled every scan is aligned to the last key scans
// (ScanMatchingOdometry) and the scan-matched pose takes the place of the
// raw odometry everywhere after this stage. A second, local matcher runs
// beside a global front end when the full smoother's motion edges are
// measured by it (smoother.motion_edges: local_match). A value: a copy is
// a snapshot of the matchers' maps and poses, and continues as the original.
#pragma once

#include <optional>

#include "ekf_slam_core/pipeline/pipeline_options.h"
#include "ekf_slam_core/scan_matching/scan_matcher.h"

namespace ekf_slam {

struct FrontEndCounters {
  long scan_matches = 0;         // scans aligned by the scan matcher
  long scan_match_refusals = 0;  // scans that fell back to the odometry increment
  // Each scan matcher's own counts, refusals by reason and the matches not
  // checked against the wheels (stamp not increasing): the front end's,
  // and the local matcher's that measures the full smoother's motion edges
  // (smoother.motion_edges: local_match) when it runs.
  ScanMatcherCounters front_end;
  bool local_matcher_runs = false;
  ScanMatcherCounters local_matcher;
};

class FrontEnd {
 public:
  explicit FrontEnd(const PipelineOptions& options);

  // The control source's pose (odom → base_link) for a scan whose raw
  // odometry is usable (usableOdometry). `usable`: the scan, its stamp and
  // its odometry can be used; otherwise the matchers only dead-reckon.
  // `check_jump`: the filter's jump rule is applied to the raw increment
  // before it becomes the match's guess (a corrupt sample must not carry
  // the front end, and the key scans of the back end, kilometres away);
  // `*jumped` tells whether it discarded the increment. Without scan
  // matching: `raw_odometry` itself.
  Pose2 track(const Scan* scan, const Pose2& raw_odometry, bool usable, bool check_jump,
              bool* jumped);

  // The filter iterated (or re-anchored) at the scan last tracked: the
  // local matcher's motion is measured from here on.
  void markIteration() {
    last_local_pose_ = local_pose_;
    local_motion_unknown_ = false;
  }
  // The local matcher's motion since the last markIteration(); empty when
  // there is no local matcher.
  std::optional<Pose2> localMotion() const;

  // True when the control is scan-matched (the wheels are then a separate
  // measurement for the full smoother).
  bool matchesScans() const { return scan_matcher_.has_value(); }

  // The scan matcher's state to continue from (a global map only), and the
  // continuation. After restore() the first iteration has no local motion
  // (the local matcher starts afresh). False when there is nothing to
  // restore into (scan matching off, a local map).
  std::optional<ScanMatchingOdometryState> state() const {
    return scan_matcher_ ? scan_matcher_->state() : std::nullopt;
  }
  bool restore(const ScanMatchingOdometryState& state) {
    if (!scan_matcher_ || !scan_matcher_->restore(state)) return false;
    local_motion_unknown_ = true;
    return true;
  }
  const FrontEndCounters& counters() const { return counters_; }

 private:
  Pose2 laser_pose_;  // base_link → laser
  ScanMatcherOptions matching_;
  double max_step_translation_ = 0.0;  // the filter's jump bounds
  double max_step_rotation_ = 0.0;
  std::optional<ScanMatchingOdometry> scan_matcher_;  // none when disabled
  // The full smoother's motion edges (FullSmootherOptions::motion_edges):
  // none unless they come from a local matcher beside a global front end.
  std::optional<ScanMatchingOdometry> local_matcher_;
  Pose2 local_pose_;       // the local matcher's pose at the scan tracked last
  Pose2 last_local_pose_;  // … and at the last iteration (or re-anchor)
  FrontEndCounters counters_;
  bool local_motion_unknown_ = false;  // after restore(), until the next iteration
};

}  // namespace ekf_slam
