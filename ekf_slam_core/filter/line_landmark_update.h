// Line landmarks in the EKF (thesis §4.3): (p, θ) lines and θ-only
// directions, their augmentation, their batched update and the
// linearisation association uses. A unit of its own beside the filter
// proper (ekf_slam.h), acting on the filter's state (filter_state.h) with
// its storage operations. EkfSlam's members of the same names call these
// and document the contracts; every function validates its input and
// leaves the state unchanged on any status other than kOk.
#pragma once

#include <vector>

#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/filter/filter_state.h"

namespace ekf_slam {
namespace lines {

// EkfSlam::updateLines.
FilterStatus update(FilterState* state, const FilterOptions& options,
                    const std::vector<LineObservation>& observations,
                    const std::vector<LineMatch>& matches, std::vector<double>* nis);
// EkfSlam::predictLineMatch.
FilterStatus predictMatch(const FilterState& state, const FilterOptions& options,
                          const LineObservation& observation, const LineMatch& match,
                          Eigen::VectorXd* innovation, Eigen::MatrixXd* innovation_covariance);
// EkfSlam::augmentLine.
FilterStatus augment(FilterState* state, const FilterOptions& options,
                     const LineObservation& observation, LandmarkKind kind, int* new_id);
// EkfSlam::addLineLandmark and EkfSlam::addLineAngleLandmark.
FilterStatus addLine(FilterState* state, int id, const PolarLine& line, const Matrix2& covariance,
                     int observations);
FilterStatus addAngle(FilterState* state, int id, double theta, double variance, int observations);
// EkfSlam::lineLandmark.
PolarLine landmark(const FilterState& state, int slot);

}  // namespace lines
}  // namespace ekf_slam
