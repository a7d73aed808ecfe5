#include "ekf_slam_core/filter/line_landmark_update.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace ekf_slam {
namespace lines {
namespace {

// One linearised line measurement: `rows` (1 or 2) rows of innovation,
// noise and Jacobian blocks on the robot and on landmark slots.
struct LinearisedLine {
  int rows = 2;
  Vector2 innovation = Vector2::Zero();
  Matrix2 noise = Matrix2::Zero();
  Matrix23 H_robot = Matrix23::Zero();
  std::vector<std::pair<int, Matrix2>> blocks;  // (slot, rows × landmark dim, top-left)
};

// A (p, θ) line landmark's predicted observation, its Jacobian blocks
// into `line` (first-estimate Jacobians where the options ask).
FilterStatus predictFullLine(const FilterState& fs, const FilterOptions& options, int slot,
                             LinearisedLine* line, PolarLine* predicted) {
  const Pose2 robot = fs.pose();
  const Pose2& laser = options.laser_pose;
  Matrix2 H_line;
  if (!predictLineObservation(robot, laser, landmark(fs, slot), predicted, &line->H_robot,
                              &H_line)) {
    return FilterStatus::kBadObservation;
  }
  if (options.first_estimate_jacobians) {
    const Vector2& first = fs.landmarks[slot].first_estimate;
    PolarLine at_first;
    if (!predictLineObservation(robot, laser, PolarLine{first(0), first(1)}, &at_first,
                                &line->H_robot, &H_line)) {
      return FilterStatus::kBadObservation;
    }
    if (std::abs(wrapAngle(at_first.theta - predicted->theta)) > 0.5 * kPi) {
      line->H_robot.row(0) *= -1.0;
      H_line.row(0) *= -1.0;
    }
  }
  line->blocks.emplace_back(slot, H_line);
  return FilterStatus::kOk;
}

// The point landmarks a θ-only match names as the line's endpoints.
FilterStatus endpointSlots(const FilterState& fs, const LineMatch& match, int endpoints[2],
                           int* count) {
  *count = 0;
  for (int e : match.endpoint_ids) {
    if (e < 0) continue;
    const int s = fs.slotOf(e);
    if (s < 0) return FilterStatus::kUnknownLandmark;
    if (fs.landmarks[s].kind != LandmarkKind::kPoint) return FilterStatus::kBadObservation;
    endpoints[(*count)++] = s;
  }
  if (*count == 2 && endpoints[0] == endpoints[1]) return FilterStatus::kBadObservation;
  return FilterStatus::kOk;
}

// A θ-only landmark without endpoints: one row, θ compared modulo π.
FilterStatus linearizeDirection(const FilterState& fs, const FilterOptions& options,
                                const LineObservation& obs, int slot, LinearisedLine* line) {
  const double theta_f = fs.x(fs.landmarkIndex(slot));
  double theta = 0.0, H_angle = 0.0;
  RowVector3 H_r;
  if (!predictLineAngle(fs.pose(), options.laser_pose, theta_f, &theta, &H_r, &H_angle)) {
    return FilterStatus::kBadObservation;
  }
  line->rows = 1;
  line->innovation(0) = lineAngleDifference(obs.z.theta, theta);
  line->noise = Matrix2::Zero();
  line->noise(0, 0) = obs.covariance(1, 1);
  line->H_robot.row(0) = H_r;
  Matrix2 block = Matrix2::Zero();
  block(0, 0) = H_angle;
  line->blocks.emplace_back(slot, block);
  return FilterStatus::kOk;
}

// A θ-only landmark with one or two endpoints (thesis eqs. 4.35, 4.38): the
// line (p, θ) they predict and its blocks on the direction and the points.
FilterStatus predictFromEndpoints(const FilterState& fs, const FilterOptions& options, int slot,
                                  const int endpoints[2], int count, LinearisedLine* line,
                                  PolarLine* predicted) {
  const Pose2 robot = fs.pose();
  const Pose2& laser = options.laser_pose;
  const double theta_f = fs.x(fs.landmarkIndex(slot));
  Matrix2 H_m1, H_m2;
  Vector2 H_angle;
  const bool ok =
      count == 1
          ? predictLineFromAngleAndPoint(robot, laser, theta_f, fs.landmarkPosition(endpoints[0]),
                                         predicted, &line->H_robot, &H_m1, &H_angle)
          : predictLineFromAngleAndEndpoints(robot, laser, theta_f,
                                             fs.landmarkPosition(endpoints[0]),
                                             fs.landmarkPosition(endpoints[1]), predicted,
                                             &line->H_robot, &H_m1, &H_m2, &H_angle);
  if (!ok) return FilterStatus::kBadObservation;
  if (options.first_estimate_jacobians) {
    const double theta_first = fs.landmarks[slot].first_estimate(1);
    const Vector2& m1 = fs.landmarks[endpoints[0]].first_estimate;
    PolarLine at_first;
    const bool ok_first =
        count == 1 ? predictLineFromAngleAndPoint(robot, laser, theta_first, m1, &at_first,
                                                  &line->H_robot, &H_m1, &H_angle)
                   : predictLineFromAngleAndEndpoints(
                         robot, laser, theta_first, m1, fs.landmarks[endpoints[1]].first_estimate,
                         &at_first, &line->H_robot, &H_m1, &H_m2, &H_angle);
    if (!ok_first) return FilterStatus::kBadObservation;
    if (std::abs(wrapAngle(at_first.theta - predicted->theta)) > 0.5 * kPi) {
      line->H_robot.row(0) *= -1.0;
      H_m1.row(0) *= -1.0;
      if (count == 2) H_m2.row(0) *= -1.0;
      H_angle(0) *= -1.0;
    }
  }
  Matrix2 angle_block = Matrix2::Zero();
  angle_block.col(0) = H_angle;
  line->blocks.emplace_back(slot, angle_block);
  line->blocks.emplace_back(endpoints[0], H_m1);
  if (count == 2) line->blocks.emplace_back(endpoints[1], H_m2);
  return FilterStatus::kOk;
}

FilterStatus linearize(const FilterState& fs, const FilterOptions& options,
                       const LineObservation& obs, const LineMatch& match, LinearisedLine* out) {
  if (!obs.z.allFinite()) return FilterStatus::kNonFiniteInput;
  if (!isValidCovariance2(obs.covariance)) return FilterStatus::kSingularInnovation;
  const int slot = fs.slotOf(match.landmark_id);
  if (slot < 0) return FilterStatus::kUnknownLandmark;
  const LandmarkKind kind = fs.landmarks[slot].kind;
  if (kind == LandmarkKind::kPoint) return FilterStatus::kBadObservation;
  LinearisedLine& line = *out;
  line = LinearisedLine();
  line.noise = obs.covariance;
  PolarLine predicted;
  if (kind == LandmarkKind::kLine) {
    const FilterStatus status = predictFullLine(fs, options, slot, &line, &predicted);
    if (status != FilterStatus::kOk) return status;
  } else {
    int endpoints[2], count = 0;
    FilterStatus status = endpointSlots(fs, match, endpoints, &count);
    if (status != FilterStatus::kOk) return status;
    if (count == 0) return linearizeDirection(fs, options, obs, slot, &line);
    status = predictFromEndpoints(fs, options, slot, endpoints, count, &line, &predicted);
    if (status != FilterStatus::kOk) return status;
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

// Line landmarks back to their normal form (p >= 0, θ wrapped), which
// leaves each line unchanged; a p crossing zero negates that row of P.
void backToNormalForm(FilterState* state) {
  FilterState& fs = *state;
  const int n = fs.dim;
  auto P = fs.P.topLeftCorner(n, n);
  for (int slot = 0; slot < fs.landmarkCount(); ++slot) {
    const int i = fs.landmarkIndex(slot);
    if (fs.landmarks[slot].kind == LandmarkKind::kLineAngle) fs.x(i) = wrapAngle(fs.x(i));
    if (fs.landmarks[slot].kind != LandmarkKind::kLine) continue;
    fs.x(i + 1) = wrapAngle(fs.x(i + 1));
    if (fs.x(i) >= 0.0) continue;
    fs.x(i) = -fs.x(i);
    fs.x(i + 1) = wrapAngle(fs.x(i + 1) + kPi);
    // The first estimate follows into the new coordinates (signed p).
    Vector2& first = fs.landmarks[slot].first_estimate;
    first = Vector2(-first(0), wrapAngle(first(1) + kPi));
    // Negate row and column i of the lower triangle (the diagonal keeps its sign).
    P.block(i, 0, 1, i) *= -1.0;
    P.block(i + 1, i, n - i - 1, 1) *= -1.0;
  }
}

}  // namespace

FilterStatus addLine(FilterState* state, int id, const PolarLine& line, const Matrix2& covariance,
                     int observations) {
  FilterState& fs = *state;
  if (!line.allFinite() || !covariance.allFinite()) return FilterStatus::kNonFiniteInput;
  if (!isValidCovariance2(covariance)) return FilterStatus::kSingularInnovation;
  // The same guards as for a point (their causes are the units' own), plus
  // θ: beyond σ = π the direction is unknown and the linearisation meaningless.
  const Eigen::SelfAdjointEigenSolver<Matrix2> eigen(0.5 * (covariance + covariance.transpose()),
                                                     Eigen::EigenvaluesOnly);
  if (eigen.eigenvalues()(1) > EkfSlam::kMaxPriorVariance ||
      eigen.eigenvalues()(0) < EkfSlam::kMinPriorEigenvalueRatio * eigen.eigenvalues()(1) ||
      covariance(1, 1) > EkfSlam::kMaxPriorAngleVariance) {
    return FilterStatus::kUnrepresentablePrior;
  }
  if (id < 0 || fs.slotOf(id) >= 0) return FilterStatus::kDuplicateLandmark;
  Vector2 mean(line.p, wrapAngle(line.theta));
  Matrix2 C = 0.5 * (covariance + covariance.transpose());
  if (line.p < 0.0) {
    mean = Vector2(-line.p, wrapAngle(line.theta + kPi));
    C(0, 1) = -C(0, 1);
    C(1, 0) = -C(1, 0);
  }
  const int n = fs.dim;
  fs.reserve(n + 2);
  // Uncorrelated with the pose and the other landmarks, as a point prior.
  fs.x.segment<2>(n) = mean;
  fs.P.block(n, 0, 2, n).setZero();
  fs.P.block(0, n, n, 2).setZero();
  fs.P.block<2, 2>(n, n) = C;
  fs.appendLandmark(LandmarkKind::kLine, id, observations, mean);
  return FilterStatus::kOk;
}

FilterStatus addAngle(FilterState* state, int id, double theta, double variance, int observations) {
  FilterState& fs = *state;
  if (!std::isfinite(theta) || !std::isfinite(variance)) return FilterStatus::kNonFiniteInput;
  if (!(variance > 0.0)) return FilterStatus::kSingularInnovation;
  if (variance > EkfSlam::kMaxPriorAngleVariance) return FilterStatus::kUnrepresentablePrior;
  if (id < 0 || fs.slotOf(id) >= 0) return FilterStatus::kDuplicateLandmark;
  const int n = fs.dim;
  fs.reserve(n + 1);
  fs.x(n) = wrapAngle(theta);
  fs.P.block(n, 0, 1, n).setZero();
  fs.P.block(0, n, n, 1).setZero();
  fs.P(n, n) = variance;
  fs.appendLandmark(LandmarkKind::kLineAngle, id, observations, Vector2(0.0, fs.x(n)));
  return FilterStatus::kOk;
}

PolarLine landmark(const FilterState& fs, int slot) {
  const int i = fs.landmarkIndex(slot);
  PolarLine line;
  if (fs.landmarks[slot].kind == LandmarkKind::kLine) {
    line.p = fs.x(i);
    line.theta = fs.x(i + 1);
  } else {
    line.theta = fs.x(i);  // a direction: no offset in the state
  }
  return line;
}

FilterStatus augment(FilterState* state, const FilterOptions& options,
                     const LineObservation& observation, LandmarkKind kind, int* new_id) {
  FilterState& fs = *state;
  if (!fs.mapping_enabled) return FilterStatus::kMappingDisabled;
  if (kind == LandmarkKind::kPoint) return FilterStatus::kBadObservation;
  if (!observation.z.allFinite()) return FilterStatus::kNonFiniteInput;
  if (!isValidCovariance2(observation.covariance)) return FilterStatus::kSingularInnovation;
  const int n = fs.dim;
  const Matrix3 P_rr = fs.P.topLeftCorner<3, 3>();
  if (kind == LandmarkKind::kLine) {
    PolarLine line;
    Matrix23 G_r;
    Matrix2 G_z, P_ll;
    if (!lineLandmarkFromObservation(fs.pose(), options.laser_pose, observation.z, &line, &G_r,
                                     &G_z) ||
        !newLineLandmarkCovariance(P_rr, observation.covariance, G_r, G_z, &P_ll)) {
      return FilterStatus::kBadObservation;
    }
    fs.reserve(n + 2);
    const Eigen::Matrix<double, 2, Eigen::Dynamic> cross = G_r * fs.P.block(0, 0, 3, n);
    fs.x.segment<2>(n) = line.vector();
    fs.P.block(n, 0, 2, n) = cross;
    fs.P.block(0, n, n, 2) = cross.transpose();
    fs.P.block<2, 2>(n, n) = P_ll;
    const int id = fs.appendLandmark(kind, fs.next_id, 1, line.vector());
    if (new_id) *new_id = id;
    return FilterStatus::kOk;
  }
  double theta_f = 0.0, variance = 0.0;
  RowVector3 G_r;
  RowVector2 G_z;
  if (!lineAngleFromObservation(fs.pose(), options.laser_pose, observation.z, &theta_f, &G_r,
                                &G_z) ||
      !newLineAngleVariance(P_rr, observation.covariance, G_r, G_z, &variance)) {
    return FilterStatus::kBadObservation;
  }
  fs.reserve(n + 1);
  const Eigen::RowVectorXd cross = G_r * fs.P.block(0, 0, 3, n);
  fs.x(n) = theta_f;
  fs.P.block(n, 0, 1, n) = cross;
  fs.P.block(0, n, n, 1) = cross.transpose();
  fs.P(n, n) = variance;
  const int id = fs.appendLandmark(kind, fs.next_id, 1, Vector2(0.0, theta_f));
  if (new_id) *new_id = id;
  return FilterStatus::kOk;
}

FilterStatus predictMatch(const FilterState& fs, const FilterOptions& options,
                          const LineObservation& observation, const LineMatch& match,
                          Eigen::VectorXd* innovation, Eigen::MatrixXd* innovation_covariance) {
  LinearisedLine line;
  const FilterStatus status = linearize(fs, options, observation, match, &line);
  if (status != FilterStatus::kOk) return status;
  // H over the few state entries it touches; P read from its lower
  // triangle, which is current everywhere.
  std::vector<int> index = {0, 1, 2};
  for (const auto& block : line.blocks) {
    const int start = fs.landmarkIndex(block.first);
    for (int d = 0; d < landmarkDim(fs.landmarks[block.first].kind); ++d)
      index.push_back(start + d);
  }
  const int m = static_cast<int>(index.size());
  const int r = line.rows;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(r, m);
  H.leftCols<3>() = line.H_robot.topRows(r);
  int column = FilterState::kPoseDim;
  for (const auto& [slot, block] : line.blocks) {
    const int d = landmarkDim(fs.landmarks[slot].kind);
    H.middleCols(column, d) = block.topLeftCorner(r, d);
    column += d;
  }
  Eigen::MatrixXd P(m, m);
  for (int a = 0; a < m; ++a) {
    for (int b = 0; b < m; ++b) {
      const int i = std::max(index[a], index[b]), j = std::min(index[a], index[b]);
      P(a, b) = fs.P(i, j);
    }
  }
  *innovation = line.innovation.head(r);
  *innovation_covariance = H * P * H.transpose() + line.noise.topLeftCorner(r, r);
  return FilterStatus::kOk;
}

FilterStatus update(FilterState* state, const FilterOptions& options,
                    const std::vector<LineObservation>& observations,
                    const std::vector<LineMatch>& matches, std::vector<double>* nis) {
  FilterState& fs = *state;
  const int k = static_cast<int>(matches.size());
  if (k == 0) {
    if (nis) nis->clear();
    return FilterStatus::kOk;
  }
  // Validate and linearise everything before touching the state.
  std::vector<LinearisedLine> lines(k);
  std::vector<char> line_used(fs.landmarkCount(), 0);
  std::vector<int> touched;
  for (int i = 0; i < k; ++i) {
    const LineMatch& match = matches[i];
    if (match.observation < 0 || match.observation >= static_cast<int>(observations.size())) {
      return FilterStatus::kBadObservation;
    }
    const FilterStatus status =
        linearize(fs, options, observations[match.observation], match, &lines[i]);
    if (status != FilterStatus::kOk) return status;
    const int slot = fs.slotOf(match.landmark_id);
    if (line_used[slot]) return FilterStatus::kBadObservation;
    line_used[slot] = 1;
    for (const auto& block : lines[i].blocks) touched.push_back(block.first);
  }

  // The same whitened downdate as update(), with H assembled from blocks.
  std::vector<int> offset(k + 1, 0);
  for (int i = 0; i < k; ++i) offset[i + 1] = offset[i] + lines[i].rows;
  const int m = offset[k];
  const int n = fs.dim;
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  fs.fillLandmarkColumns(touched);
  auto P = fs.P.topLeftCorner(n, n);
  Eigen::MatrixXd PHt(n, m);
  Eigen::MatrixXd S(m, m);
  Eigen::VectorXd innovation(m);
  for (int i = 0; i < k; ++i) {
    const LinearisedLine& line = lines[i];
    const int r = line.rows;
    PHt.middleCols(offset[i], r).noalias() = P.leftCols<3>() * line.H_robot.topRows(r).transpose();
    for (const auto& [slot, H] : line.blocks) {
      const int d = landmarkDim(fs.landmarks[slot].kind);
      PHt.middleCols(offset[i], r).noalias() +=
          P.middleCols(fs.landmarkIndex(slot), d) * H.topLeftCorner(r, d).transpose();
    }
    innovation.segment(offset[i], r) = line.innovation.head(r);
  }
  for (int i = 0; i < k; ++i) {
    const LinearisedLine& line = lines[i];
    const int r = line.rows;
    S.middleRows(offset[i], r).noalias() = line.H_robot.topRows(r) * PHt.topRows<3>();
    for (const auto& [slot, H] : line.blocks) {
      const int d = landmarkDim(fs.landmarks[slot].kind);
      S.middleRows(offset[i], r).noalias() +=
          H.topLeftCorner(r, d) * PHt.middleRows(fs.landmarkIndex(slot), d);
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
  fs.applyGain(PHt, llt, innovation);
  backToNormalForm(&fs);
  fs.mirrorPoseRowsAndLandmarkBlocks();
  for (int i = 0; i < k; ++i) {
    for (const auto& [slot, H] : lines[i].blocks) {
      if (fs.landmarks[slot].kind == LandmarkKind::kPoint) continue;  // endpoints: seen as points
      ++fs.landmarks[slot].observations;
      fs.landmarks[slot].last_seen_step = fs.step;
    }
  }
  return FilterStatus::kOk;
}

}  // namespace lines
}  // namespace ekf_slam
