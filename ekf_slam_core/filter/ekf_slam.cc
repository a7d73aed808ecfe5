#include "ekf_slam_core/filter/ekf_slam.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <cmath>

namespace ekf_slam {
namespace {

bool isFiniteMatrix(const Eigen::Ref<const Eigen::MatrixXd>& m) { return m.allFinite(); }

// A 2×2 covariance must be finite, symmetric and positive definite.
bool isValidCovariance2(const Matrix2& c) {
  return c.allFinite() && std::abs(c(0, 1) - c(1, 0)) <= 1e-9 * (1.0 + c.cwiseAbs().maxCoeff()) &&
         c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0;
}

// Symmetrises the stacked innovation covariance S and factors it; kOk
// when S = L Lᵀ with a positive diagonal.
FilterStatus factorInnovation(Eigen::MatrixXd* S, Eigen::LLT<Eigen::MatrixXd>* llt) {
  *S = 0.5 * (*S + S->transpose()).eval();
  if (!isFiniteMatrix(*S)) return FilterStatus::kNonFiniteInput;
  llt->compute(*S);
  if (llt->info() != Eigen::Success || !(llt->matrixLLT().diagonal().minCoeff() > 0.0)) {
    return FilterStatus::kSingularInnovation;
  }
  return FilterStatus::kOk;
}

}  // namespace

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

const char* toString(LandmarkKind kind) {
  switch (kind) {
    case LandmarkKind::kPoint:
      return "point";
    case LandmarkKind::kLine:
      return "line";
    case LandmarkKind::kLineAngle:
      return "line_angle";
  }
  return "unknown";
}

std::string FilterOptions::validate() const {
  if (!laser_pose.allFinite()) return "laser_pose must be finite";
  return checkFields(*this);
}

EkfSlam::EkfSlam(const FilterOptions& options, const Pose2& initial_pose,
                 const Matrix3& initial_covariance)
    : options_(options) {
  assert(options_.validate().empty());
  reserve(64);
  x_.head<3>() = initial_pose.vector();
  P_.topLeftCorner<3, 3>() = 0.5 * (initial_covariance + initial_covariance.transpose());
}

void EkfSlam::reserve(int dim) {
  if (x_.size() >= dim) return;
  const int capacity = std::max(dim, static_cast<int>(2 * x_.size()));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(capacity);
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(capacity, capacity);
  if (x_.size() > 0) {
    x.head(dim_) = x_.head(dim_);
    P.topLeftCorner(dim_, dim_) = P_.topLeftCorner(dim_, dim_);
  }
  x_.swap(x);
  P_.swap(P);
}

int EkfSlam::slotOf(int id) const {
  const auto it = slot_of_id_.find(id);
  return it == slot_of_id_.end() ? -1 : it->second;
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
    if (have_prior_position_) {
      F(0, 2) = -(predicted.y - prior_position_.y());
      F(1, 2) = predicted.x - prior_position_.x();
    }
    prior_position_ = predicted.translation();
    have_prior_position_ = true;
  }

  x_.head<3>() = predicted.vector();
  const int m = dim_ - kPoseDim;
  // Only the robot rows/columns change: P_rr = F P_rr Fᵀ + G Q Gᵀ, P_rm = F P_rm.
  const Matrix3 P_rr = P_.topLeftCorner<3, 3>();
  const Matrix3 P_rr_new = F * P_rr * F.transpose() + G * Q * G.transpose();
  P_.topLeftCorner<3, 3>() = 0.5 * (P_rr_new + P_rr_new.transpose());  // exactly symmetric
  if (m > 0) {
    const Eigen::Matrix<double, 3, Eigen::Dynamic> P_rm = F * P_.block(0, kPoseDim, 3, m);
    P_.block(0, kPoseDim, 3, m) = P_rm;
    P_.block(kPoseDim, 0, m, 3) = P_rm.transpose();
  }
  last_F_ = F;
  ++step_;
  return FilterStatus::kOk;
}

bool EkfSlam::predictObservation(int slot, Prediction* out) const {
  assert(slot >= 0 && slot < landmarkCount());
  if (landmarks_[slot].kind != LandmarkKind::kPoint) return false;
  const int j = landmarkIndex(slot);
  if (!predictPointObservation(pose(), options_.laser_pose, landmarkPosition(slot), &out->z,
                               &out->H_robot, &out->H_landmark)) {
    return false;
  }
  if (options_.first_estimate_jacobians) {
    // The prediction from the current estimate, the Jacobians at the
    // landmark's first estimate.
    RangeBearing unused;
    if (!predictPointObservation(pose(), options_.laser_pose, landmarks_[slot].first_estimate,
                                 &unused, &out->H_robot, &out->H_landmark)) {
      return false;
    }
  }
  const Matrix23& Hr = out->H_robot;
  const Matrix2& Hm = out->H_landmark;
  const Matrix2 cross = Hr * P_.block<3, 2>(0, j) * Hm.transpose();
  out->HPHt = Hr * P_.topLeftCorner<3, 3>() * Hr.transpose() + cross + cross.transpose() +
              Hm * P_.block<2, 2>(j, j) * Hm.transpose();
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

  const int n = dim_;
  fillLandmarkColumns(slots);
  auto P = P_.topLeftCorner(n, n);
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

  applyGain(PHt, llt, innovation);
  mirrorPoseRowsAndLandmarkBlocks();

  for (int i = 0; i < k; ++i) {
    LandmarkInfo& info = landmarks_[slots[i]];
    ++info.observations;
    info.last_seen_step = step_;
  }
  return FilterStatus::kOk;
}

void EkfSlam::applyGain(const Eigen::MatrixXd& PHt, const Eigen::LLT<Eigen::MatrixXd>& llt,
                        const Eigen::VectorXd& innovation) {
  // With S = L Lᵀ and W = P Hᵀ L⁻ᵀ:  x += W L⁻¹ ν,  P −= W Wᵀ.
  const int n = dim_;
  const Eigen::MatrixXd Wt = llt.matrixL().solve(PHt.transpose());  // rows of ν × n
  const Eigen::VectorXd whitened = llt.matrixL().solve(innovation);
  x_.head(n).noalias() += Wt.transpose() * whitened;
  x_(2) = wrapAngle(x_(2));
  P_.topLeftCorner(n, n).selfadjointView<Eigen::Lower>().rankUpdate(Wt.transpose(), -1.0);
}

void EkfSlam::mirrorPoseRowsAndLandmarkBlocks() {
  // After a downdate of the lower triangle, O(n): the upper triangle of the
  // pose rows and of each landmark's 2 × 2 block, which the predictions read.
  const int n = dim_;
  P_(0, 1) = P_(1, 0);
  P_(0, 2) = P_(2, 0);
  P_(1, 2) = P_(2, 1);
  P_.block(0, kPoseDim, kPoseDim, n - kPoseDim) =
      P_.block(kPoseDim, 0, n - kPoseDim, kPoseDim).transpose();
  for (const LandmarkInfo& info : landmarks_) {
    if (landmarkDim(info.kind) == 2)
      P_(info.index, info.index + 1) = P_(info.index + 1, info.index);
  }
}

void EkfSlam::fillLandmarkColumns(const std::vector<int>& slots) {
  // Rows 0–2 and the 2 × 2 blocks are current; the rows of the earlier
  // landmarks come from the lower triangle, O(n) per landmark. The source is
  // a row of the column-major storage, one column (and page) per entry: all
  // landmarks take a tile of columns in turn so that its pages are reused.
  constexpr int kTile = 64;
  int end = kPoseDim;
  for (int slot : slots) end = std::max(end, landmarkIndex(slot));
  for (int c0 = kPoseDim; c0 < end; c0 += kTile) {
    for (int slot : slots) {
      const int j = landmarkIndex(slot);
      const int dim = landmarkDim(landmarks_[slot].kind);
      const int count = std::min(c0 + kTile, j) - c0;
      if (count <= 0) continue;
      P_.block(c0, j, count, dim) = P_.block(j, c0, dim, count).transpose();
    }
  }
}

Eigen::MatrixXd EkfSlam::covariance() const {
  return P_.topLeftCorner(dim_, dim_).selfadjointView<Eigen::Lower>();
}

Matrix2 EkfSlam::landmarkCrossCovariance(int slot_a, int slot_b) const {
  const int ja = landmarkIndex(slot_a), jb = landmarkIndex(slot_b);
  if (ja >= jb) return P_.block<2, 2>(ja, jb);
  return P_.block<2, 2>(jb, ja).transpose();
}

FilterStatus EkfSlam::augment(const PointObservation& observation, int* new_id) {
  if (!mapping_enabled_) return FilterStatus::kMappingDisabled;
  if (!std::isfinite(observation.z.range) || !std::isfinite(observation.z.bearing)) {
    return FilterStatus::kNonFiniteInput;
  }
  if (!isValidCovariance2(observation.covariance)) return FilterStatus::kSingularInnovation;
  if (!(observation.z.range > 0.0)) return FilterStatus::kBadObservation;

  Matrix23 G_r;
  Matrix2 G_z;
  const Vector2 m = landmarkFromObservation(pose(), options_.laser_pose, observation.z, &G_r, &G_z);
  const int n = dim_;
  reserve(n + kPointDim);
  // New rows: P_m,all = G_r P_r,all;  P_mm = G_r P_rr G_rᵀ + G_z R G_zᵀ.
  const Eigen::Matrix<double, 2, Eigen::Dynamic> cross = G_r * P_.block(0, 0, 3, n);
  x_.segment<2>(n) = m;
  P_.block(n, 0, 2, n) = cross;
  P_.block(0, n, n, 2) = cross.transpose();
  const Matrix2 P_mm = G_r * P_.topLeftCorner<3, 3>() * G_r.transpose() +
                       G_z * observation.covariance * G_z.transpose();
  P_.block<2, 2>(n, n) = 0.5 * (P_mm + P_mm.transpose());
  const int id = appendLandmark(LandmarkKind::kPoint, next_id_, 1, m);
  if (new_id) *new_id = id;
  return FilterStatus::kOk;
}

int EkfSlam::appendLandmark(LandmarkKind kind, int id, int observations,
                            const Vector2& first_estimate) {
  LandmarkInfo info;
  info.id = id;
  info.kind = kind;
  info.index = dim_;
  info.first_estimate = first_estimate;
  info.observations = std::max(1, observations);
  info.created_step = step_;
  info.last_seen_step = step_;
  dim_ += landmarkDim(kind);
  slot_of_id_[id] = landmarkCount();
  landmarks_.push_back(info);
  next_id_ = std::max(next_id_, id + 1);
  return id;
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
  const int n = dim_;
  reserve(n + kPointDim);
  // A prior map is known independently of where the robot is now: the new
  // rows and columns carry no correlation with the pose or other landmarks.
  x_.segment<2>(n) = position;
  P_.block(n, 0, 2, n).setZero();
  P_.block(0, n, n, 2).setZero();
  P_.block<2, 2>(n, n) = 0.5 * (covariance + covariance.transpose());
  appendLandmark(LandmarkKind::kPoint, id, observations, position);
  return FilterStatus::kOk;
}

FilterStatus EkfSlam::addLineLandmark(int id, const PolarLine& line, const Matrix2& covariance,
                                      int observations) {
  if (!line.allFinite() || !covariance.allFinite()) return FilterStatus::kNonFiniteInput;
  if (!isValidCovariance2(covariance)) return FilterStatus::kSingularInnovation;
  // The same guards as for a point (their causes are the units' own), plus
  // θ: beyond σ = π the direction is unknown and the linearisation meaningless.
  const Eigen::SelfAdjointEigenSolver<Matrix2> eigen(0.5 * (covariance + covariance.transpose()),
                                                     Eigen::EigenvaluesOnly);
  if (eigen.eigenvalues()(1) > kMaxPriorVariance ||
      eigen.eigenvalues()(0) < kMinPriorEigenvalueRatio * eigen.eigenvalues()(1) ||
      covariance(1, 1) > kMaxPriorAngleVariance) {
    return FilterStatus::kUnrepresentablePrior;
  }
  if (id < 0 || slotOf(id) >= 0) return FilterStatus::kDuplicateLandmark;
  Vector2 mean(line.p, wrapAngle(line.theta));
  Matrix2 C = 0.5 * (covariance + covariance.transpose());
  if (line.p < 0.0) {
    mean = Vector2(-line.p, wrapAngle(line.theta + kPi));
    C(0, 1) = -C(0, 1);
    C(1, 0) = -C(1, 0);
  }
  const int n = dim_;
  reserve(n + 2);
  // Uncorrelated with the pose and the other landmarks, as a point prior.
  x_.segment<2>(n) = mean;
  P_.block(n, 0, 2, n).setZero();
  P_.block(0, n, n, 2).setZero();
  P_.block<2, 2>(n, n) = C;
  appendLandmark(LandmarkKind::kLine, id, observations, mean);
  return FilterStatus::kOk;
}

FilterStatus EkfSlam::addLineAngleLandmark(int id, double theta, double variance,
                                           int observations) {
  if (!std::isfinite(theta) || !std::isfinite(variance)) return FilterStatus::kNonFiniteInput;
  if (!(variance > 0.0)) return FilterStatus::kSingularInnovation;
  if (variance > kMaxPriorAngleVariance) return FilterStatus::kUnrepresentablePrior;
  if (id < 0 || slotOf(id) >= 0) return FilterStatus::kDuplicateLandmark;
  const int n = dim_;
  reserve(n + 1);
  x_(n) = wrapAngle(theta);
  P_.block(n, 0, 1, n).setZero();
  P_.block(0, n, n, 1).setZero();
  P_(n, n) = variance;
  appendLandmark(LandmarkKind::kLineAngle, id, observations, Vector2(0.0, x_(n)));
  return FilterStatus::kOk;
}

int EkfSlam::pruneTentative() {
  if (options_.tentative_max_age <= 0) return 0;
  std::vector<int> slots;
  for (int s = 0; s < landmarkCount(); ++s) {
    const LandmarkInfo& info = landmarks_[s];
    if (info.observations <= 1 && step_ - info.created_step >= options_.tentative_max_age) {
      slots.push_back(s);
    }
  }
  removeSlots(slots);
  return static_cast<int>(slots.size());
}

FilterStatus EkfSlam::mergeLandmarks(int keep_id, int drop_id, double gate, double bias_sigma) {
  const int a = slotOf(keep_id), b = slotOf(drop_id);
  if (a < 0 || b < 0 || a == b) return FilterStatus::kUnknownLandmark;
  if (landmarks_[a].kind != LandmarkKind::kPoint || landmarks_[b].kind != LandmarkKind::kPoint) {
    return FilterStatus::kBadObservation;
  }
  const int n = dim_;
  const int ia = landmarkIndex(a), ib = landmarkIndex(b);
  fillLandmarkColumns({a, b});
  auto P = P_.topLeftCorner(n, n);
  // H = [… I … −I …] picks x_a − x_b; P Hᵀ and S = H P Hᵀ are column blocks.
  const Eigen::MatrixXd PHt = P.middleCols<2>(ia) - P.middleCols<2>(ib);  // n × 2
  Matrix2 S = PHt.middleRows<2>(ia) - PHt.middleRows<2>(ib);
  S = 0.5 * (S + S.transpose()).eval();
  S += bias_sigma * bias_sigma * Matrix2::Identity();
  const Vector2 difference = x_.segment<2>(ia) - x_.segment<2>(ib);
  const Eigen::LLT<Matrix2> llt(S);
  if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().minCoeff() > 0.0)) {
    return FilterStatus::kSingularInnovation;
  }
  if (!(difference.dot(llt.solve(difference)) < gate)) return FilterStatus::kBadObservation;
  // Condition on x_a − x_b = 0 (noise b²I): x −= W L⁻¹ d, P −= W Wᵀ with
  // W = P Hᵀ L⁻ᵀ.
  const Eigen::MatrixXd Wt = llt.matrixL().solve(PHt.transpose());  // 2 × n
  const Vector2 whitened = llt.matrixL().solve(difference);
  x_.head(n).noalias() -= Wt.transpose() * whitened;
  x_(2) = wrapAngle(x_(2));
  P.selfadjointView<Eigen::Lower>().rankUpdate(Wt.transpose(), -1.0);
  mirrorPoseRowsAndLandmarkBlocks();
  LandmarkInfo& kept = landmarks_[a];
  const LandmarkInfo& dropped = landmarks_[b];
  kept.observations += dropped.observations;
  kept.last_seen_step = std::max(kept.last_seen_step, dropped.last_seen_step);
  removeSlots({b});
  return FilterStatus::kOk;
}

std::vector<std::pair<int, int>> EkfSlam::mergeDuplicates(const std::vector<int>& ids, double gate,
                                                          double max_distance, double bias_sigma) {
  std::vector<std::pair<int, int>> merged;
  for (int id : ids) {
    bool again = true;
    while (again) {  // a landmark may have several twins
      again = false;
      const int slot = slotOf(id);
      if (slot < 0) break;  // merged away already
      if (landmarks_[slot].kind != LandmarkKind::kPoint) break;
      const Vector2 position = landmarkPosition(slot);
      for (int other = 0; other < landmarkCount(); ++other) {
        if (other == slot || landmarks_[other].kind != LandmarkKind::kPoint) continue;
        if ((landmarkPosition(other) - position).squaredNorm() > max_distance * max_distance) {
          continue;
        }
        // Keep the older landmark (smaller id: created first).
        const int other_id = landmarks_[other].id;
        const int keep = std::min(id, other_id), drop = std::max(id, other_id);
        if (mergeLandmarks(keep, drop, gate, bias_sigma) == FilterStatus::kOk) {
          merged.emplace_back(keep, drop);
          id = keep;
          again = true;
          break;
        }
      }
    }
  }
  return merged;
}

bool EkfSlam::removeLandmark(int id) {
  const int slot = slotOf(id);
  if (slot < 0) return false;
  removeSlots({slot});
  return true;
}

int EkfSlam::removeLandmarks(const std::vector<int>& ids) {
  std::vector<int> slots;
  slots.reserve(ids.size());
  for (int id : ids) {
    const int slot = slotOf(id);
    if (slot >= 0) slots.push_back(slot);
  }
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  removeSlots(slots);
  return static_cast<int>(slots.size());
}

void EkfSlam::removeSlots(const std::vector<int>& slots) {
  if (slots.empty()) return;
  std::vector<char> drop(landmarkCount(), 0);
  for (int s : slots) drop[s] = 1;
  // The kept state indices as runs (old start, new start, length): the pose,
  // then each stretch of consecutive kept landmarks.
  struct Run {
    int from, to, length;
  };
  std::vector<Run> runs = {{0, 0, kPoseDim}};
  int n = kPoseDim;
  for (int s = 0; s < landmarkCount(); ++s) {
    if (drop[s]) continue;
    const int from = landmarkIndex(s);
    const int dim = landmarkDim(landmarks_[s].kind);
    if (runs.size() > 1 && runs.back().from + runs.back().length == from) {
      runs.back().length += dim;
    } else {
      runs.push_back({from, n, dim});
    }
    n += dim;
  }
  // Move the kept entries down within the storage, column by column in
  // increasing order, each run of kept rows to its new place. No index grows,
  // so every entry is read before anything is written over it, also within a
  // column, where rows only move up. Entries already in place are skipped: a
  // removal of the newest landmarks moves nothing, one in the middle only what
  // lies beyond it. No n × n temporary: on large maps, allocating and filling
  // one costs far more than the update. Of the upper triangle only the pose
  // rows and the landmarks' 2 × 2 blocks are current (see the header), so
  // column c needs rows 0–2 and rows from c − 1 on.
  double* const x = x_.data();
  for (const Run& rows : runs) {
    if (rows.from != rows.to) std::copy(x + rows.from, x + rows.from + rows.length, x + rows.to);
  }
  for (const Run& cols : runs) {
    for (int k = 0; k < cols.length; ++k) {
      const int c = cols.to + k;
      const double* const from = &P_(0, cols.from + k);
      double* const to = &P_(0, c);
      for (const Run& rows : runs) {
        if (cols.from == cols.to && rows.from == rows.to) continue;
        // Rows [to + skip, to + length) of this run are needed in column c.
        const int skip = rows.to == 0 ? 0 : std::max(0, c - 1 - rows.to);
        if (skip >= rows.length) continue;
        std::copy(from + rows.from + skip, from + rows.from + rows.length, to + rows.to + skip);
      }
    }
  }
  dim_ = n;

  int kept = 0, index = kPoseDim;
  for (int s = 0; s < static_cast<int>(drop.size()); ++s) {
    if (drop[s]) {
      slot_of_id_.erase(landmarks_[s].id);
      continue;
    }
    if (kept != s) {
      landmarks_[kept] = landmarks_[s];
      slot_of_id_[landmarks_[kept].id] = kept;
    }
    landmarks_[kept].index = index;
    index += landmarkDim(landmarks_[kept].kind);
    ++kept;
  }
  landmarks_.resize(kept);
}

void EkfSlam::reanchor(const Pose2& robot_correction,
                       const std::vector<std::pair<int, Pose2>>& landmark_corrections) {
  const int n = dim_;
  // The stored upper triangle is only partly current: fill it from the
  // lower one so that the row and column passes below see the whole P (a
  // loop closure is rare; this O(n²) pass allocates nothing).
  for (int c = 0; c < n; ++c) {
    for (int r = c + 1; r < n; ++r) P_(c, r) = P_(r, c);
  }
  // The Jacobian acting on each 2-row block (robot position, then each
  // point or line landmark); identity where nothing moves. A direction
  // (kLineAngle) only shifts: its rows of P stay.
  std::vector<Matrix2> rotation(1 + landmarkCount(), Matrix2::Identity());
  std::vector<char> moved(1 + landmarkCount(), 0);
  const Pose2 robot = compose(robot_correction, pose());
  x_(0) = robot.x;
  x_(1) = robot.y;
  x_(2) = robot.theta;
  rotation[0] = robot_correction.rotation();
  moved[0] = 1;
  if (have_prior_position_) prior_position_ = transformFrom(robot_correction, prior_position_);
  for (const auto& [id, correction] : landmark_corrections) {
    const int slot = slotOf(id);
    if (slot < 0) continue;
    const int i = landmarkIndex(slot);
    switch (landmarks_[slot].kind) {
      case LandmarkKind::kPoint:
        x_.segment<2>(i) = transformFrom(correction, Vector2(x_.segment<2>(i)));
        landmarks_[slot].first_estimate =
            transformFrom(correction, landmarks_[slot].first_estimate);
        rotation[1 + slot] = correction.rotation();
        moved[1 + slot] = 1;
        break;
      case LandmarkKind::kLine: {
        const double theta = x_(i + 1) + correction.theta;
        const Vector2 normal(std::cos(theta), std::sin(theta));
        const double p = x_(i) + normal.dot(correction.translation());
        const double sign = p < 0.0 ? -1.0 : 1.0;
        x_(i) = sign * p;
        x_(i + 1) = wrapAngle(sign < 0.0 ? theta + kPi : theta);
        rotation[1 + slot] << sign,
            sign * Vector2(-normal.y(), normal.x()).dot(correction.translation()), 0.0, 1.0;
        moved[1 + slot] = 1;
        // The first estimate moves as the line, into the same coordinates.
        Vector2& first = landmarks_[slot].first_estimate;
        const double first_theta = first(1) + correction.theta;
        const double first_p =
            first(0) +
            Vector2(std::cos(first_theta), std::sin(first_theta)).dot(correction.translation());
        first = Vector2(sign * first_p, wrapAngle(sign < 0.0 ? first_theta + kPi : first_theta));
        break;
      }
      case LandmarkKind::kLineAngle:
        x_(i) = wrapAngle(x_(i) + correction.theta);
        landmarks_[slot].first_estimate(1) =
            wrapAngle(landmarks_[slot].first_estimate(1) + correction.theta);
        break;
    }
  }
  // P ↦ J P Jᵀ, block by block: rows of block a by R_a, columns of block b by R_bᵀ.
  // The robot's heading row/column (index 2) is not rotated.
  auto start = [this](int block) { return block == 0 ? 0 : landmarkIndex(block - 1); };
  const int blocks = 1 + landmarkCount();
  for (int a = 0; a < blocks; ++a) {
    if (!moved[a]) continue;
    const int ia = start(a);
    P_.block(ia, 0, 2, n) = rotation[a] * P_.block(ia, 0, 2, n);
  }
  for (int b = 0; b < blocks; ++b) {
    if (!moved[b]) continue;
    const int ib = start(b);
    P_.block(0, ib, n, 2) = P_.block(0, ib, n, 2) * rotation[b].transpose();
  }
  // Exactly symmetric again (the two passes round differently), in place.
  for (int c = 0; c < n; ++c) {
    for (int r = c + 1; r < n; ++r) {
      const double v = 0.5 * (P_(r, c) + P_(c, r));
      P_(r, c) = v;
      P_(c, r) = v;
    }
  }
}

PolarLine EkfSlam::lineLandmark(int slot) const {
  const int i = landmarkIndex(slot);
  PolarLine line;
  if (landmarks_[slot].kind == LandmarkKind::kLine) {
    line.p = x_(i);
    line.theta = x_(i + 1);
  } else {
    line.theta = x_(i);  // a direction: no offset in the state
  }
  return line;
}

FilterStatus EkfSlam::augmentLine(const LineObservation& observation, LandmarkKind kind,
                                  int* new_id) {
  if (!mapping_enabled_) return FilterStatus::kMappingDisabled;
  if (kind == LandmarkKind::kPoint) return FilterStatus::kBadObservation;
  if (!observation.z.allFinite()) return FilterStatus::kNonFiniteInput;
  if (!isValidCovariance2(observation.covariance)) return FilterStatus::kSingularInnovation;
  const int n = dim_;
  const Matrix3 P_rr = P_.topLeftCorner<3, 3>();
  if (kind == LandmarkKind::kLine) {
    PolarLine line;
    Matrix23 G_r;
    Matrix2 G_z, P_ll;
    if (!lineLandmarkFromObservation(pose(), options_.laser_pose, observation.z, &line, &G_r,
                                     &G_z) ||
        !newLineLandmarkCovariance(P_rr, observation.covariance, G_r, G_z, &P_ll)) {
      return FilterStatus::kBadObservation;
    }
    reserve(n + 2);
    const Eigen::Matrix<double, 2, Eigen::Dynamic> cross = G_r * P_.block(0, 0, 3, n);
    x_.segment<2>(n) = line.vector();
    P_.block(n, 0, 2, n) = cross;
    P_.block(0, n, n, 2) = cross.transpose();
    P_.block<2, 2>(n, n) = P_ll;
    const int id = appendLandmark(kind, next_id_, 1, line.vector());
    if (new_id) *new_id = id;
    return FilterStatus::kOk;
  }
  double theta_f = 0.0, variance = 0.0;
  RowVector3 G_r;
  RowVector2 G_z;
  if (!lineAngleFromObservation(pose(), options_.laser_pose, observation.z, &theta_f, &G_r, &G_z) ||
      !newLineAngleVariance(P_rr, observation.covariance, G_r, G_z, &variance)) {
    return FilterStatus::kBadObservation;
  }
  reserve(n + 1);
  const Eigen::RowVectorXd cross = G_r * P_.block(0, 0, 3, n);
  x_(n) = theta_f;
  P_.block(n, 0, 1, n) = cross;
  P_.block(0, n, n, 1) = cross.transpose();
  P_(n, n) = variance;
  const int id = appendLandmark(kind, next_id_, 1, Vector2(0.0, theta_f));
  if (new_id) *new_id = id;
  return FilterStatus::kOk;
}

// One linearised line measurement: `rows` (1 or 2) rows of innovation,
// noise and Jacobian blocks on the robot and on landmark slots.
struct EkfSlam::LinearisedLine {
  int rows = 2;
  Vector2 innovation = Vector2::Zero();
  Matrix2 noise = Matrix2::Zero();
  Matrix23 H_robot = Matrix23::Zero();
  std::vector<std::pair<int, Matrix2>> blocks;  // (slot, rows × landmark dim, top-left)
};

FilterStatus EkfSlam::linearizeLineMatch(const LineObservation& obs, const LineMatch& match,
                                         LinearisedLine* out) const {
  if (!obs.z.allFinite()) return FilterStatus::kNonFiniteInput;
  if (!isValidCovariance2(obs.covariance)) return FilterStatus::kSingularInnovation;
  const int slot = slotOf(match.landmark_id);
  if (slot < 0) return FilterStatus::kUnknownLandmark;
  const LandmarkKind kind = landmarks_[slot].kind;
  if (kind == LandmarkKind::kPoint) return FilterStatus::kBadObservation;
  const Pose2 robot = pose();
  const Pose2& laser = options_.laser_pose;
  LinearisedLine& line = *out;
  line = LinearisedLine();
  line.noise = obs.covariance;
  PolarLine predicted;
  if (kind == LandmarkKind::kLine) {
    Matrix2 H_line;
    if (!predictLineObservation(robot, laser, lineLandmark(slot), &predicted, &line.H_robot,
                                &H_line)) {
      return FilterStatus::kBadObservation;
    }
    if (options_.first_estimate_jacobians) {
      const Vector2& first = landmarks_[slot].first_estimate;
      PolarLine at_first;
      if (!predictLineObservation(robot, laser, PolarLine{first(0), first(1)}, &at_first,
                                  &line.H_robot, &H_line)) {
        return FilterStatus::kBadObservation;
      }
      if (std::abs(wrapAngle(at_first.theta - predicted.theta)) > 0.5 * kPi) {
        line.H_robot.row(0) *= -1.0;
        H_line.row(0) *= -1.0;
      }
    }
    line.blocks.emplace_back(slot, H_line);
  } else {
    int endpoints[2], count = 0;
    for (int e : match.endpoint_ids) {
      if (e < 0) continue;
      const int s = slotOf(e);
      if (s < 0) return FilterStatus::kUnknownLandmark;
      if (landmarks_[s].kind != LandmarkKind::kPoint) return FilterStatus::kBadObservation;
      endpoints[count++] = s;
    }
    if (count == 2 && endpoints[0] == endpoints[1]) return FilterStatus::kBadObservation;
    const double theta_f = lineAngle(slot);
    if (count == 0) {  // θ alone, modulo π
      double theta = 0.0, H_angle = 0.0;
      RowVector3 H_r;
      if (!predictLineAngle(robot, laser, theta_f, &theta, &H_r, &H_angle)) {
        return FilterStatus::kBadObservation;
      }
      line.rows = 1;
      line.innovation(0) = lineAngleDifference(obs.z.theta, theta);
      line.noise = Matrix2::Zero();
      line.noise(0, 0) = obs.covariance(1, 1);
      line.H_robot.row(0) = H_r;
      Matrix2 block = Matrix2::Zero();
      block(0, 0) = H_angle;
      line.blocks.emplace_back(slot, block);
      return FilterStatus::kOk;
    }
    Matrix2 H_m1, H_m2;
    Vector2 H_angle;
    const bool ok =
        count == 1
            ? predictLineFromAngleAndPoint(robot, laser, theta_f, landmarkPosition(endpoints[0]),
                                           &predicted, &line.H_robot, &H_m1, &H_angle)
            : predictLineFromAngleAndEndpoints(robot, laser, theta_f,
                                               landmarkPosition(endpoints[0]),
                                               landmarkPosition(endpoints[1]), &predicted,
                                               &line.H_robot, &H_m1, &H_m2, &H_angle);
    if (!ok) return FilterStatus::kBadObservation;
    if (options_.first_estimate_jacobians) {
      const double theta_first = landmarks_[slot].first_estimate(1);
      const Vector2& m1 = landmarks_[endpoints[0]].first_estimate;
      PolarLine at_first;
      const bool ok_first =
          count == 1 ? predictLineFromAngleAndPoint(robot, laser, theta_first, m1, &at_first,
                                                    &line.H_robot, &H_m1, &H_angle)
                     : predictLineFromAngleAndEndpoints(
                           robot, laser, theta_first, m1, landmarks_[endpoints[1]].first_estimate,
                           &at_first, &line.H_robot, &H_m1, &H_m2, &H_angle);
      if (!ok_first) return FilterStatus::kBadObservation;
      if (std::abs(wrapAngle(at_first.theta - predicted.theta)) > 0.5 * kPi) {
        line.H_robot.row(0) *= -1.0;
        H_m1.row(0) *= -1.0;
        if (count == 2) H_m2.row(0) *= -1.0;
        H_angle(0) *= -1.0;
      }
    }
    Matrix2 angle_block = Matrix2::Zero();
    angle_block.col(0) = H_angle;
    line.blocks.emplace_back(slot, angle_block);
    line.blocks.emplace_back(endpoints[0], H_m1);
    if (count == 2) line.blocks.emplace_back(endpoints[1], H_m2);
  }
  // ν = z − ẑ with the p-sign and θ-wrap ambiguity resolved towards ẑ;
  // ∂ν/∂ẑ = −flip, so the measurement Jacobian is flip · H.
  Matrix2 J;
  if (!lineInnovation(obs.z, predicted, &line.innovation, &J)) {
    return FilterStatus::kBadObservation;
  }
  const Matrix2 flip = -J;
  line.H_robot = flip * line.H_robot;
  for (auto& block : line.blocks) block.second = flip * block.second;
  return FilterStatus::kOk;
}

FilterStatus EkfSlam::predictLineMatch(const LineObservation& observation, const LineMatch& match,
                                       Eigen::VectorXd* innovation,
                                       Eigen::MatrixXd* innovation_covariance) const {
  LinearisedLine line;
  const FilterStatus status = linearizeLineMatch(observation, match, &line);
  if (status != FilterStatus::kOk) return status;
  // H over the few state entries it touches; P read from its lower
  // triangle, which is current everywhere.
  std::vector<int> index = {0, 1, 2};
  for (const auto& block : line.blocks) {
    const int start = landmarkIndex(block.first);
    for (int d = 0; d < landmarkDim(landmarks_[block.first].kind); ++d) index.push_back(start + d);
  }
  const int m = static_cast<int>(index.size());
  const int r = line.rows;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(r, m);
  H.leftCols<3>() = line.H_robot.topRows(r);
  int column = kPoseDim;
  for (const auto& [slot, block] : line.blocks) {
    const int d = landmarkDim(landmarks_[slot].kind);
    H.middleCols(column, d) = block.topLeftCorner(r, d);
    column += d;
  }
  Eigen::MatrixXd P(m, m);
  for (int a = 0; a < m; ++a) {
    for (int b = 0; b < m; ++b) {
      const int i = std::max(index[a], index[b]), j = std::min(index[a], index[b]);
      P(a, b) = P_(i, j);
    }
  }
  *innovation = line.innovation.head(r);
  *innovation_covariance = H * P * H.transpose() + line.noise.topLeftCorner(r, r);
  return FilterStatus::kOk;
}

FilterStatus EkfSlam::updateLines(const std::vector<LineObservation>& observations,
                                  const std::vector<LineMatch>& matches, std::vector<double>* nis) {
  const int k = static_cast<int>(matches.size());
  if (k == 0) {
    if (nis) nis->clear();
    return FilterStatus::kOk;
  }
  // Validate and linearise everything before touching the state.
  std::vector<LinearisedLine> lines(k);
  std::vector<char> line_used(landmarkCount(), 0);
  std::vector<int> touched;
  for (int i = 0; i < k; ++i) {
    const LineMatch& match = matches[i];
    if (match.observation < 0 || match.observation >= static_cast<int>(observations.size())) {
      return FilterStatus::kBadObservation;
    }
    const FilterStatus status =
        linearizeLineMatch(observations[match.observation], match, &lines[i]);
    if (status != FilterStatus::kOk) return status;
    const int slot = slotOf(match.landmark_id);
    if (line_used[slot]) return FilterStatus::kBadObservation;
    line_used[slot] = 1;
    for (const auto& block : lines[i].blocks) touched.push_back(block.first);
  }

  // The same whitened downdate as update(), with H assembled from blocks.
  std::vector<int> offset(k + 1, 0);
  for (int i = 0; i < k; ++i) offset[i + 1] = offset[i] + lines[i].rows;
  const int m = offset[k];
  const int n = dim_;
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  fillLandmarkColumns(touched);
  auto P = P_.topLeftCorner(n, n);
  Eigen::MatrixXd PHt(n, m);
  Eigen::MatrixXd S(m, m);
  Eigen::VectorXd innovation(m);
  for (int i = 0; i < k; ++i) {
    const LinearisedLine& line = lines[i];
    const int r = line.rows;
    PHt.middleCols(offset[i], r).noalias() = P.leftCols<3>() * line.H_robot.topRows(r).transpose();
    for (const auto& [slot, H] : line.blocks) {
      const int d = landmarkDim(landmarks_[slot].kind);
      PHt.middleCols(offset[i], r).noalias() +=
          P.middleCols(landmarkIndex(slot), d) * H.topLeftCorner(r, d).transpose();
    }
    innovation.segment(offset[i], r) = line.innovation.head(r);
  }
  for (int i = 0; i < k; ++i) {
    const LinearisedLine& line = lines[i];
    const int r = line.rows;
    S.middleRows(offset[i], r).noalias() = line.H_robot.topRows(r) * PHt.topRows<3>();
    for (const auto& [slot, H] : line.blocks) {
      const int d = landmarkDim(landmarks_[slot].kind);
      S.middleRows(offset[i], r).noalias() +=
          H.topLeftCorner(r, d) * PHt.middleRows(landmarkIndex(slot), d);
    }
    S.block(offset[i], offset[i], r, r) += line.noise.topLeftCorner(r, r);
  }
  Eigen::LLT<Eigen::MatrixXd> llt;
  const FilterStatus factored = factorInnovation(&S, &llt);
  if (factored != FilterStatus::kOk) return factored;
  if (nis) {
    nis->resize(k);
    for (int i = 0; i < k; ++i) {
      const int r = lines[i].rows;
      const Eigen::VectorXd v = innovation.segment(offset[i], r);
      (*nis)[i] = v.dot(S.block(offset[i], offset[i], r, r).ldlt().solve(v));
    }
  }
  applyGain(PHt, llt, innovation);
  // Line landmarks back to their normal form (p >= 0, θ wrapped), which
  // leaves the line unchanged; a p crossing zero negates that row of P.
  for (int slot = 0; slot < landmarkCount(); ++slot) {
    const int i = landmarkIndex(slot);
    if (landmarks_[slot].kind == LandmarkKind::kLineAngle) x_(i) = wrapAngle(x_(i));
    if (landmarks_[slot].kind != LandmarkKind::kLine) continue;
    x_(i + 1) = wrapAngle(x_(i + 1));
    if (x_(i) >= 0.0) continue;
    x_(i) = -x_(i);
    x_(i + 1) = wrapAngle(x_(i + 1) + kPi);
    // The first estimate follows into the new coordinates (signed p).
    Vector2& first = landmarks_[slot].first_estimate;
    first = Vector2(-first(0), wrapAngle(first(1) + kPi));
    // Negate row and column i of the lower triangle (the diagonal keeps its sign).
    P.block(i, 0, 1, i) *= -1.0;
    P.block(i + 1, i, n - i - 1, 1) *= -1.0;
  }
  mirrorPoseRowsAndLandmarkBlocks();
  for (int i = 0; i < k; ++i) {
    for (const auto& [slot, H] : lines[i].blocks) {
      if (landmarks_[slot].kind == LandmarkKind::kPoint) continue;  // endpoints: seen as points
      ++landmarks_[slot].observations;
      landmarks_[slot].last_seen_step = step_;
    }
  }
  return FilterStatus::kOk;
}

double EkfSlam::poseNees(const Pose2& truth) const {
  Vector3 error = truth.vector() - x_.head<3>();
  error(2) = wrapAngle(error(2));
  return error.dot(poseCovariance().ldlt().solve(error));
}

}  // namespace ekf_slam
