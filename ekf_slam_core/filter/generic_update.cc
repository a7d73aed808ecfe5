// EkfSlam::updateGeneric: the EKF update for an observation whose model
// lives outside the filter (the MECP centre of mecp/mecp_update.h). Kept in
// its own file: the filter's own point observations stay in ekf_slam.cc.
#include <Eigen/Cholesky>

#include "ekf_slam_core/filter/ekf_slam.h"

namespace ekf_slam {

FilterStatus EkfSlam::updateGeneric(const GenericObservation& observation, double* nis) {
  const Eigen::VectorXd& innovation = observation.innovation;
  const int d = static_cast<int>(innovation.size());
  const int count = static_cast<int>(observation.landmark_ids.size());
  // Validate everything before touching the state.
  if (d == 0 || observation.J_z_pose.rows() != d || observation.J_z_pose.cols() != kPoseDim ||
      observation.noise.rows() != d || observation.noise.cols() != d ||
      static_cast<int>(observation.J_z_landmarks.size()) != count) {
    return FilterStatus::kBadObservation;
  }
  if (!innovation.allFinite() || !observation.J_z_pose.allFinite() ||
      !observation.noise.allFinite()) {
    return FilterStatus::kNonFiniteInput;
  }
  std::vector<int> slots(count);
  for (int i = 0; i < count; ++i) {
    slots[i] = slotOf(observation.landmark_ids[i]);
    if (slots[i] < 0) return FilterStatus::kUnknownLandmark;
    for (int k = 0; k < i; ++k) {
      if (slots[k] == slots[i]) return FilterStatus::kBadObservation;
    }
    const Eigen::MatrixXd& J = observation.J_z_landmarks[i];
    if (J.rows() != d || J.cols() != landmarkDim(state_.landmarks[slots[i]].kind)) {
      return FilterStatus::kBadObservation;
    }
    if (!J.allFinite()) return FilterStatus::kNonFiniteInput;
  }

  const int n = state_.dim;
  state_.fillLandmarkColumns(slots);
  auto P = state_.P.topLeftCorner(n, n);
  // P Hᵀ (n × d) from the sparse H: the pose's and the listed landmarks'
  // column blocks only.
  Eigen::MatrixXd PHt = P.leftCols<kPoseDim>() * observation.J_z_pose.transpose();
  for (int i = 0; i < count; ++i) {
    const Eigen::MatrixXd& J = observation.J_z_landmarks[i];
    PHt.noalias() += P.middleCols(landmarkIndex(slots[i]), J.cols()) * J.transpose();
  }
  Eigen::MatrixXd S = observation.J_z_pose * PHt.topRows<kPoseDim>() + observation.noise;
  for (int i = 0; i < count; ++i) {
    const Eigen::MatrixXd& J = observation.J_z_landmarks[i];
    S.noalias() += J * PHt.middleRows(landmarkIndex(slots[i]), J.cols());
  }
  S = 0.5 * (S + S.transpose()).eval();
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().minCoeff() > 0.0)) {
    return FilterStatus::kSingularInnovation;
  }
  if (nis) *nis = innovation.dot(llt.solve(innovation));
  state_.applyGain(PHt, llt, innovation);
  state_.mirrorPoseRowsAndLandmarkBlocks();
  return FilterStatus::kOk;
}

}  // namespace ekf_slam
