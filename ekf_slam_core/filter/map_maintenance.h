// The map's upkeep in the EKF state: tentative landmarks pruned, landmarks
// removed, duplicates merged by conditioning on their difference, and the
// whole map re-anchored when a loop-closing back end moves the key scans.
// A unit of its own beside the filter proper (ekf_slam.h), acting on the
// filter's state (filter_state.h) with its storage operations. EkfSlam's
// members of the same purpose call these and document the contracts.
#pragma once

#include <utility>
#include <vector>

#include "ekf_slam_core/filter/filter_state.h"

namespace ekf_slam {
namespace maintenance {

// EkfSlam::pruneTentative, with options().tentative_max_age as `max_age`
// (0: keep all).
int pruneTentative(FilterState* state, long max_age);
// EkfSlam::removeLandmark and EkfSlam::removeLandmarks.
bool remove(FilterState* state, int id);
int removeAll(FilterState* state, const std::vector<int>& ids);
// EkfSlam::mergeLandmarks and EkfSlam::mergeDuplicates.
FilterStatus merge(FilterState* state, int keep_id, int drop_id, double gate, double bias_sigma);
std::vector<std::pair<int, int>> mergeDuplicates(FilterState* state, const std::vector<int>& ids,
                                                 double gate, double max_distance,
                                                 double bias_sigma);
// EkfSlam::reanchor.
void reanchor(FilterState* state, const Pose2& robot_correction,
              const std::vector<std::pair<int, Pose2>>& landmark_corrections);

}  // namespace maintenance
}  // namespace ekf_slam
