// The pipeline's filter stage: the EKF (thesis Ch. 2–3) over the robot's
// pose and the landmarks, with its strategies beside the point landmarks
// (wall lines, MECP association, room gating) and the map's maintenance (landmarks
// seen too rarely are pruned; beyond max_landmarks the least recently
// matched are marginalised out). The coordinator predicts with the front
// end's control, then hands each iterated scan's features to update() and,
// once the history has recorded the iteration, to maintain().
#pragma once

#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/mecp/mecp_association.h"
#include "ekf_slam_core/pipeline/filter_strategies.h"
#include "ekf_slam_core/pipeline/line_landmarks.h"
#include "ekf_slam_core/pipeline/pipeline_options.h"
#include "ekf_slam_core/pipeline/scan_result.h"

namespace ekf_slam {

struct PointCounters {
  long update_failures = 0;  // iterations whose update was refused
  long observations = 0;     // landmark candidates offered to the filter
  long matches = 0;
  long ambiguous = 0;  // between the gates, or lost to a better observation
  long new_landmarks = 0;
  double nis_sum = 0.0;   // over all matches
  long pruned = 0;        // tentative landmarks removed
  long pruned_rare = 0;   // landmarks removed by prune_min_observations
  long marginalised = 0;  // landmarks dropped by the max_landmarks bound
  long reanchors = 0;     // times the filter took the loop-closed geometry
};

struct LineCounters {
  long line_observations = 0;  // wall segments offered to the filter (after the length/range gate)
  long line_matches = 0;
  long line_endpoint_matches = 0;  // of those: θ-only, the offset from endpoint points
  long line_ambiguous = 0;
  long new_line_landmarks = 0;
  long lines_refused = 0;         // segments with non-finite values or covariance
  long line_update_failures = 0;  // iterations whose line update was refused
  double line_nis_sum = 0.0;      // over all line matches
};

// Everything the filter stage counts: its own and its strategies'.
struct FilterCounters : PointCounters, LineCounters, MecpCounters, RoomCounters {};

class LocalFilter {
 public:
  explicit LocalFilter(const PipelineOptions& options);

  // The prediction from the control source's poses at the last iteration
  // and now (EkfSlam::predict).
  FilterStatus predict(const Pose2& from, const Pose2& to, double dt, bool check_jump) {
    return filter_.predict(from, to, dt, check_jump);
  }
  // The observation half of an iteration on out->features: the point
  // landmark candidates within range are associated (gated by rooms when
  // on, and each scan's polygon by MECP with points+mecp), used in one
  // update and the new ones augmented; then the lines. Fills out->observations,
  // observation_feature, iteration, lines.
  void update(ScanResult* out);
  // After the history recorded the iteration: the counts, the map's
  // maintenance, and the strategies' upkeep (line extents, rooms).
  void maintain(const ScanResult& result);
  // The loop-closed geometry: the robot moved by `robot_correction`, each
  // listed landmark by its transform (BackEndLink::reanchorCorrections).
  void reanchor(const Pose2& robot_correction,
                const std::vector<std::pair<int, Pose2>>& corrections);

  // The pose of a scan between iterations: the filter's pose moved by the
  // control since `anchor` (the control source's pose at the last
  // iteration), and its covariance as a prediction would carry it (F P Fᵀ +
  // G Q Gᵀ), without touching the filter.
  Pose2 deadReckoned(const Pose2& anchor, const Pose2& odometry) const;
  Matrix3 deadReckonedCovariance(const Pose2& anchor, const Pose2& odometry) const;

  const EkfSlam& filter() const { return filter_; }
  EkfSlam& mutableFilter() { return filter_; }
  const std::unordered_map<int, LineSupport>& lineSupport() const;
  void seedLineSupport(const std::unordered_map<int, LineSupport>& support);
  const RoomGate* roomGate() const { return rooms_ ? rooms_->gate() : nullptr; }
  FilterCounters counters() const;

 private:
  int pruneRarelySeen();  // returns how many landmarks were removed
  int boundLandmarks();   // max_landmarks; returns how many were marginalised

  PipelineOptions options_;
  EkfSlam filter_;
  std::optional<LineLandmarks> lines_;       // none with points only
  std::optional<MecpAssociation> mecp_;      // landmarks: points+mecp
  std::optional<RoomGatingStrategy> rooms_;  // rooms.enabled
  PointCounters points_;
  LineCounters lines_counted_;
};

}  // namespace ekf_slam
