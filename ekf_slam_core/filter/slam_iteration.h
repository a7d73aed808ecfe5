// One EKF-SLAM iteration (thesis §2.4): predict from odometry, associate the
// scan's point observations, update with all matches in one batch, augment
// the new landmarks, and prune tentative landmarks. The same function serves
// the live node, the offline runner, the demo and the benchmarks.
#pragma once

#include <functional>
#include <utility>
#include <vector>

#include "ekf_slam_core/filter/data_association.h"
#include "ekf_slam_core/filter/ekf_slam.h"

namespace ekf_slam {

struct IterationReport {
  FilterStatus predict_status = FilterStatus::kOk;
  FilterStatus update_status = FilterStatus::kOk;
  AssociationResult association;
  std::vector<PointMatch> matches;
  std::vector<double> nis;            // per match, same order
  std::vector<int> new_landmark_ids;  // landmarks added this iteration
  std::vector<PointMatch> created;  // the observation each new landmark was made from (same order)
  int augment_failures = 0;         // new-landmark observations refused
  int pruned = 0;                   // tentative landmarks removed
  std::vector<std::pair<int, int>> merged;  // duplicate landmarks fused: (kept id, dropped id)

  bool ok() const {
    return predict_status == FilterStatus::kOk && update_status == FilterStatus::kOk;
  }
};

// When the prediction is refused (bad time step, odometry jump, NaN) the
// observations are not used: they cannot be placed without a pose. The
// caller decides how to re-anchor its odometry (see docs).
IterationReport runIteration(EkfSlam& filter, const AssociationOptions& association,
                             const Pose2& odom_previous, const Pose2& odom_current, double dt,
                             const std::vector<PointObservation>& observations);

// An association in place of associate() (the same contract): e.g. one
// that never pairs across rooms (mecp/room_gating.h).
using Associator = std::function<AssociationResult(
    const EkfSlam&, const std::vector<PointObservation>&, const AssociationOptions&)>;

// The observation half of an iteration (associate, update, augment, prune),
// for a caller that ran the prediction itself or has none (the first scan).
// `associator`, when given, replaces associate().
void observe(EkfSlam& filter, const AssociationOptions& association,
             const std::vector<PointObservation>& observations, IterationReport* report,
             const Associator& associator = nullptr);

}  // namespace ekf_slam
