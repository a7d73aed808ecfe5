#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/filter/line_landmark_update.h"
#include "ekf_slam_core/filter/map_maintenance.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <cmath>

namespace ekf_slam {

const char* toString(FilterStatus status) {
  switch (status) {
    case FilterStatus::kOk:
      return "ok";
    case FilterStatus::kNonFiniteInput:
      return "non-finite input";
    case FilterStatus::kBadTimeStep:
      return "time step not positive";
    case FilterStatus::kOdometryJump:
      return "odometry jump beyond bounds";
    case FilterStatus::kSingularInnovation:
      return "innovation covariance not positive definite";
    case FilterStatus::kUnknownLandmark:
      return "unknown landmark";
    case FilterStatus::kBadObservation:
      return "observation undefined (landmark at sensor origin)";
    case FilterStatus::kMappingDisabled:
      return "new landmarks disabled (localisation only)";
    case FilterStatus::kDuplicateLandmark:
      return "a landmark with this id exists";
    case FilterStatus::kUnrepresentablePrior:
      return "prior covariance beyond what the filter can represent";
  }
  return "unknown status";
}

std::string FilterOptions::validate() const {
  if (!laser_pose.allFinite()) return "laser_pose must be finite";
  return checkFields(*this);
}

EkfSlam::EkfSlam(const FilterOptions& options, const Pose2& initial_pose,
                 const Matrix3& initial_covariance)
    : options_(options), state_(initial_pose, initial_covariance) {
  assert(options_.validate().empty());
}

FilterStatus EkfSlam::predict(const Pose2& odom_previous, const Pose2& odom_current, double dt,
                              bool jump_check) {
  if (!odom_previous.allFinite() || !odom_current.allFinite()) return FilterStatus::kNonFiniteInput;
  return predict(controlFromOdometry(odom_previous, odom_current), dt, jump_check);
}

FilterStatus EkfSlam::predict(const OdometryControl& u, double dt, bool jump_check) {
  if (!u.allFinite() || !std::isfinite(dt)) return FilterStatus::kNonFiniteInput;
  if (!(dt > 0.0)) return FilterStatus::kBadTimeStep;
  if (jump_check && options_.isJump(u)) {
    return FilterStatus::kOdometryJump;
  }
  Matrix3 F, G;
  const Pose2 predicted = applyControl(pose(), u, &F, &G);
  const Matrix3 Q = controlCovariance(u, options_.motion_noise);
  if (options_.first_estimate_jacobians) {
    // F's heading column is (−Δy, Δx) of the motion; take Δ between the
    // predicted positions of this and the previous step, not from the
    // corrected one.
    if (state_.have_prior_position) {
      F(0, 2) = -(predicted.y - state_.prior_position.y());
      F(1, 2) = predicted.x - state_.prior_position.x();
    }
    state_.prior_position = predicted.translation();
    state_.have_prior_position = true;
  }

  state_.x.head<3>() = predicted.vector();
  const int m = state_.dim - kPoseDim;
  // Only the robot rows/columns change: P_rr = F P_rr Fᵀ + G Q Gᵀ, P_rm = F P_rm.
  const Matrix3 P_rr = state_.P.topLeftCorner<3, 3>();
  const Matrix3 P_rr_new = F * P_rr * F.transpose() + G * Q * G.transpose();
  state_.P.topLeftCorner<3, 3>() = 0.5 * (P_rr_new + P_rr_new.transpose());  // exactly symmetric
  if (m > 0) {
    const Eigen::Matrix<double, 3, Eigen::Dynamic> P_rm = F * state_.P.block(0, kPoseDim, 3, m);
    state_.P.block(0, kPoseDim, 3, m) = P_rm;
    state_.P.block(kPoseDim, 0, m, 3) = P_rm.transpose();
  }
  state_.last_F = F;
  ++state_.step;
  return FilterStatus::kOk;
}

bool EkfSlam::predictObservation(int slot, Prediction* out) const {
  assert(slot >= 0 && slot < landmarkCount());
  if (state_.landmarks[slot].kind != LandmarkKind::kPoint) return false;
  const int j = landmarkIndex(slot);
  if (!predictPointObservation(pose(), options_.laser_pose, landmarkPosition(slot), &out->z,
                               &out->H_robot, &out->H_landmark)) {
    return false;
  }
  if (options_.first_estimate_jacobians) {
    // The prediction from the current estimate, the Jacobians at the
    // landmark's first estimate.
    RangeBearing unused;
    if (!predictPointObservation(pose(), options_.laser_pose, state_.landmarks[slot].first_estimate,
                                 &unused, &out->H_robot, &out->H_landmark)) {
      return false;
    }
  }
  const Matrix23& Hr = out->H_robot;
  const Matrix2& Hm = out->H_landmark;
  const Matrix2 cross = Hr * state_.P.block<3, 2>(0, j) * Hm.transpose();
  out->HPHt = Hr * state_.P.topLeftCorner<3, 3>() * Hr.transpose() + cross + cross.transpose() +
              Hm * state_.P.block<2, 2>(j, j) * Hm.transpose();
  return true;
}

FilterStatus EkfSlam::update(const std::vector<PointObservation>& observations,
                             const std::vector<PointMatch>& matches, std::vector<double>* nis) {
  const int k = static_cast<int>(matches.size());
  if (k == 0) {
    if (nis) nis->clear();
    return FilterStatus::kOk;
  }
  // Validate everything before touching the state.
  std::vector<int> slots(k);
  std::vector<Prediction> predictions(k);
  std::vector<char> landmark_used(landmarkCount(), 0);
  for (int i = 0; i < k; ++i) {
    const PointMatch& match = matches[i];
    if (match.observation < 0 || match.observation >= static_cast<int>(observations.size())) {
      return FilterStatus::kBadObservation;
    }
    const PointObservation& obs = observations[match.observation];
    if (!std::isfinite(obs.z.range) || !std::isfinite(obs.z.bearing)) {
      return FilterStatus::kNonFiniteInput;
    }
    if (!isValidCovariance2(obs.covariance)) return FilterStatus::kSingularInnovation;
    slots[i] = slotOf(match.landmark_id);
    if (slots[i] < 0) return FilterStatus::kUnknownLandmark;
    if (landmark_used[slots[i]]) return FilterStatus::kBadObservation;  // one match per landmark
    landmark_used[slots[i]] = 1;
    if (!predictObservation(slots[i], &predictions[i])) return FilterStatus::kBadObservation;
  }

  const int n = state_.dim;
  state_.fillLandmarkColumns(slots);
  auto P = state_.P.topLeftCorner(n, n);
  // P Hᵀ (n × 2k) from the sparse H: only robot and one landmark column block each.
  Eigen::MatrixXd PHt(n, 2 * k);
  for (int i = 0; i < k; ++i) {
    const int j = landmarkIndex(slots[i]);
    PHt.middleCols<2>(2 * i).noalias() = P.leftCols<3>() * predictions[i].H_robot.transpose();
    PHt.middleCols<2>(2 * i).noalias() +=
        P.middleCols<2>(j) * predictions[i].H_landmark.transpose();
  }
  // S = H P Hᵀ + R (2k × 2k), innovation ν.
  Eigen::MatrixXd S(2 * k, 2 * k);
  Eigen::VectorXd innovation(2 * k);
  for (int i = 0; i < k; ++i) {
    const int j = landmarkIndex(slots[i]);
    S.middleRows<2>(2 * i).noalias() = predictions[i].H_robot * PHt.topRows<3>();
    S.middleRows<2>(2 * i).noalias() += predictions[i].H_landmark * PHt.middleRows<2>(j);
    const PointObservation& obs = observations[matches[i].observation];
    S.block<2, 2>(2 * i, 2 * i) += obs.covariance;
    innovation(2 * i) = obs.z.range - predictions[i].z.range;
    innovation(2 * i + 1) = wrapAngle(obs.z.bearing - predictions[i].z.bearing);
  }
  Eigen::LLT<Eigen::MatrixXd> llt;
  const FilterStatus factored = factorInnovation(&S, &llt);
  if (factored != FilterStatus::kOk) return factored;

  if (nis) {
    nis->resize(k);
    for (int i = 0; i < k; ++i) {
      const Eigen::Vector2d v = innovation.segment<2>(2 * i);
      (*nis)[i] = v.dot(S.block<2, 2>(2 * i, 2 * i).ldlt().solve(v));
    }
  }

  state_.applyGain(PHt, llt, innovation);
  state_.mirrorPoseRowsAndLandmarkBlocks();

  for (int i = 0; i < k; ++i) {
    LandmarkInfo& info = state_.landmarks[slots[i]];
    ++info.observations;
    info.last_seen_step = state_.step;
  }
  return FilterStatus::kOk;
}

FilterStatus EkfSlam::augment(const PointObservation& observation, int* new_id) {
  if (!state_.mapping_enabled) return FilterStatus::kMappingDisabled;
  if (!std::isfinite(observation.z.range) || !std::isfinite(observation.z.bearing)) {
    return FilterStatus::kNonFiniteInput;
  }
  if (!isValidCovariance2(observation.covariance)) return FilterStatus::kSingularInnovation;
  if (!(observation.z.range > 0.0)) return FilterStatus::kBadObservation;

  Matrix23 G_r;
  Matrix2 G_z;
  const Vector2 m = landmarkFromObservation(pose(), options_.laser_pose, observation.z, &G_r, &G_z);
  const int n = state_.dim;
  state_.reserve(n + kPointDim);
  // New rows: P_m,all = G_r P_r,all;  P_mm = G_r P_rr G_rᵀ + G_z R G_zᵀ.
  const Eigen::Matrix<double, 2, Eigen::Dynamic> cross = G_r * state_.P.block(0, 0, 3, n);
  state_.x.segment<2>(n) = m;
  state_.P.block(n, 0, 2, n) = cross;
  state_.P.block(0, n, n, 2) = cross.transpose();
  const Matrix2 P_mm = G_r * state_.P.topLeftCorner<3, 3>() * G_r.transpose() +
                       G_z * observation.covariance * G_z.transpose();
  state_.P.block<2, 2>(n, n) = 0.5 * (P_mm + P_mm.transpose());
  const int id = state_.appendLandmark(LandmarkKind::kPoint, state_.next_id, 1, m);
  if (new_id) *new_id = id;
  return FilterStatus::kOk;
}

FilterStatus EkfSlam::addLandmark(int id, const Vector2& position, const Matrix2& covariance,
                                  int observations) {
  if (!position.allFinite() || !covariance.allFinite()) return FilterStatus::kNonFiniteInput;
  if (!isValidCovariance2(covariance)) return FilterStatus::kSingularInnovation;
  // An update against a variance of 1e300 m² cancels catastrophically (P
  // minus a gain term equal to it up to rounding) and leaves P indefinite;
  // a nearly singular one does the same in one direction.
  const Eigen::SelfAdjointEigenSolver<Matrix2> eigen(0.5 * (covariance + covariance.transpose()),
                                                     Eigen::EigenvaluesOnly);
  if (eigen.eigenvalues()(1) > kMaxPriorVariance ||
      eigen.eigenvalues()(0) < kMinPriorEigenvalueRatio * eigen.eigenvalues()(1)) {
    return FilterStatus::kUnrepresentablePrior;
  }
  if (id < 0 || slotOf(id) >= 0) return FilterStatus::kDuplicateLandmark;
  const int n = state_.dim;
  state_.reserve(n + kPointDim);
  // A prior map is known independently of where the robot is now: the new
  // rows and columns carry no correlation with the pose or other landmarks.
  state_.x.segment<2>(n) = position;
  state_.P.block(n, 0, 2, n).setZero();
  state_.P.block(0, n, n, 2).setZero();
  state_.P.block<2, 2>(n, n) = 0.5 * (covariance + covariance.transpose());
  state_.appendLandmark(LandmarkKind::kPoint, id, observations, position);
  return FilterStatus::kOk;
}

double EkfSlam::poseNees(const Pose2& truth) const {
  Vector3 error = truth.vector() - state_.x.head<3>();
  error(2) = wrapAngle(error(2));
  return error.dot(poseCovariance().ldlt().solve(error));
}

// The line landmarks and the map's upkeep: their own units.

FilterStatus EkfSlam::updateLines(const std::vector<LineObservation>& observations,
                                  const std::vector<LineMatch>& matches, std::vector<double>* nis) {
  return lines::update(&state_, options_, observations, matches, nis);
}

FilterStatus EkfSlam::predictLineMatch(const LineObservation& observation, const LineMatch& match,
                                       Eigen::VectorXd* innovation,
                                       Eigen::MatrixXd* innovation_covariance) const {
  return lines::predictMatch(state_, options_, observation, match, innovation,
                             innovation_covariance);
}

FilterStatus EkfSlam::augmentLine(const LineObservation& observation, LandmarkKind kind,
                                  int* new_id) {
  return lines::augment(&state_, options_, observation, kind, new_id);
}

PolarLine EkfSlam::lineLandmark(int slot) const { return lines::landmark(state_, slot); }

FilterStatus EkfSlam::addLineLandmark(int id, const PolarLine& line, const Matrix2& covariance,
                                      int observations) {
  return lines::addLine(&state_, id, line, covariance, observations);
}

FilterStatus EkfSlam::addLineAngleLandmark(int id, double theta, double variance,
                                           int observations) {
  return lines::addAngle(&state_, id, theta, variance, observations);
}

int EkfSlam::pruneTentative() {
  return maintenance::pruneTentative(&state_, options_.tentative_max_age);
}

bool EkfSlam::removeLandmark(int id) { return maintenance::remove(&state_, id); }

int EkfSlam::removeLandmarks(const std::vector<int>& ids) {
  return maintenance::removeAll(&state_, ids);
}

FilterStatus EkfSlam::mergeLandmarks(int keep_id, int drop_id, double gate, double bias_sigma) {
  return maintenance::merge(&state_, keep_id, drop_id, gate, bias_sigma);
}

std::vector<std::pair<int, int>> EkfSlam::mergeDuplicates(const std::vector<int>& ids, double gate,
                                                          double max_distance, double bias_sigma) {
  return maintenance::mergeDuplicates(&state_, ids, gate, max_distance, bias_sigma);
}

void EkfSlam::reanchor(const Pose2& robot_correction,
                       const std::vector<std::pair<int, Pose2>>& landmark_corrections) {
  maintenance::reanchor(&state_, robot_correction, landmark_corrections);
}

}  // namespace ekf_slam
