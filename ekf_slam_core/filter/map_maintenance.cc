#include "ekf_slam_core/filter/map_maintenance.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace ekf_slam {
namespace maintenance {

int pruneTentative(FilterState* state, long max_age) {
  FilterState& fs = *state;
  if (max_age <= 0) return 0;
  std::vector<int> slots;
  for (int s = 0; s < fs.landmarkCount(); ++s) {
    const LandmarkInfo& info = fs.landmarks[s];
    if (info.observations <= 1 && fs.step - info.created_step >= max_age) {
      slots.push_back(s);
    }
  }
  fs.removeSlots(slots);
  return static_cast<int>(slots.size());
}

FilterStatus merge(FilterState* state, int keep_id, int drop_id, double gate, double bias_sigma) {
  FilterState& fs = *state;
  const int a = fs.slotOf(keep_id), b = fs.slotOf(drop_id);
  if (a < 0 || b < 0 || a == b) return FilterStatus::kUnknownLandmark;
  if (fs.landmarks[a].kind != LandmarkKind::kPoint ||
      fs.landmarks[b].kind != LandmarkKind::kPoint) {
    return FilterStatus::kBadObservation;
  }
  const int n = fs.dim;
  const int ia = fs.landmarkIndex(a), ib = fs.landmarkIndex(b);
  fs.fillLandmarkColumns({a, b});
  auto P = fs.P.topLeftCorner(n, n);
  // H = [… I … −I …] picks x_a − x_b; P Hᵀ and S = H P Hᵀ are column blocks.
  const Eigen::MatrixXd PHt = P.middleCols<2>(ia) - P.middleCols<2>(ib);  // n × 2
  Matrix2 S = PHt.middleRows<2>(ia) - PHt.middleRows<2>(ib);
  S = 0.5 * (S + S.transpose()).eval();
  S += bias_sigma * bias_sigma * Matrix2::Identity();
  const Vector2 difference = fs.x.segment<2>(ia) - fs.x.segment<2>(ib);
  const Eigen::LLT<Matrix2> llt(S);
  if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().minCoeff() > 0.0)) {
    return FilterStatus::kSingularInnovation;
  }
  if (!(difference.dot(llt.solve(difference)) < gate)) return FilterStatus::kBadObservation;
  // Condition on x_a − x_b = 0 (noise b²I): x −= W L⁻¹ d, P −= W Wᵀ with
  // W = P Hᵀ L⁻ᵀ.
  const Eigen::MatrixXd Wt = llt.matrixL().solve(PHt.transpose());  // 2 × n
  const Vector2 whitened = llt.matrixL().solve(difference);
  fs.x.head(n).noalias() -= Wt.transpose() * whitened;
  fs.x(2) = wrapAngle(fs.x(2));
  P.selfadjointView<Eigen::Lower>().rankUpdate(Wt.transpose(), -1.0);
  fs.mirrorPoseRowsAndLandmarkBlocks();
  LandmarkInfo& kept = fs.landmarks[a];
  const LandmarkInfo& dropped = fs.landmarks[b];
  kept.observations += dropped.observations;
  kept.last_seen_step = std::max(kept.last_seen_step, dropped.last_seen_step);
  fs.removeSlots({b});
  return FilterStatus::kOk;
}

std::vector<std::pair<int, int>> mergeDuplicates(FilterState* state, const std::vector<int>& ids,
                                                 double gate, double max_distance,
                                                 double bias_sigma) {
  FilterState& fs = *state;
  std::vector<std::pair<int, int>> merged;
  for (int id : ids) {
    bool again = true;
    while (again) {  // a landmark may have several twins
      again = false;
      const int slot = fs.slotOf(id);
      if (slot < 0) break;  // merged away already
      if (fs.landmarks[slot].kind != LandmarkKind::kPoint) break;
      const Vector2 position = fs.landmarkPosition(slot);
      for (int other = 0; other < fs.landmarkCount(); ++other) {
        if (other == slot || fs.landmarks[other].kind != LandmarkKind::kPoint) continue;
        if ((fs.landmarkPosition(other) - position).squaredNorm() > max_distance * max_distance) {
          continue;
        }
        // Keep the older landmark (smaller id: created first).
        const int other_id = fs.landmarks[other].id;
        const int keep = std::min(id, other_id), drop = std::max(id, other_id);
        if (merge(state, keep, drop, gate, bias_sigma) == FilterStatus::kOk) {
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

bool remove(FilterState* state, int id) {
  FilterState& fs = *state;
  const int slot = fs.slotOf(id);
  if (slot < 0) return false;
  fs.removeSlots({slot});
  return true;
}

int removeAll(FilterState* state, const std::vector<int>& ids) {
  FilterState& fs = *state;
  std::vector<int> slots;
  slots.reserve(ids.size());
  for (int id : ids) {
    const int slot = fs.slotOf(id);
    if (slot >= 0) slots.push_back(slot);
  }
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  fs.removeSlots(slots);
  return static_cast<int>(slots.size());
}

void reanchor(FilterState* state, const Pose2& robot_correction,
              const std::vector<std::pair<int, Pose2>>& landmark_corrections) {
  FilterState& fs = *state;
  const int n = fs.dim;
  // The stored upper triangle is only partly current: fill it from the
  // lower one so that the row and column passes below see the whole P (a
  // loop closure is rare; this O(n²) pass allocates nothing).
  for (int c = 0; c < n; ++c) {
    for (int r = c + 1; r < n; ++r) fs.P(c, r) = fs.P(r, c);
  }
  // The Jacobian acting on each 2-row block (robot position, then each
  // point or line landmark); identity where nothing moves. A direction
  // (kLineAngle) only shifts: its rows of P stay.
  std::vector<Matrix2> rotation(1 + fs.landmarkCount(), Matrix2::Identity());
  std::vector<char> moved(1 + fs.landmarkCount(), 0);
  const Pose2 robot = compose(robot_correction, fs.pose());
  fs.x(0) = robot.x;
  fs.x(1) = robot.y;
  fs.x(2) = robot.theta;
  rotation[0] = robot_correction.rotation();
  moved[0] = 1;
  if (fs.have_prior_position)
    fs.prior_position = transformFrom(robot_correction, fs.prior_position);
  for (const auto& [id, correction] : landmark_corrections) {
    const int slot = fs.slotOf(id);
    if (slot < 0) continue;
    const int i = fs.landmarkIndex(slot);
    switch (fs.landmarks[slot].kind) {
      case LandmarkKind::kPoint:
        fs.x.segment<2>(i) = transformFrom(correction, Vector2(fs.x.segment<2>(i)));
        fs.landmarks[slot].first_estimate =
            transformFrom(correction, fs.landmarks[slot].first_estimate);
        rotation[1 + slot] = correction.rotation();
        moved[1 + slot] = 1;
        break;
      case LandmarkKind::kLine: {
        const double theta = fs.x(i + 1) + correction.theta;
        const Vector2 normal(std::cos(theta), std::sin(theta));
        const double p = fs.x(i) + normal.dot(correction.translation());
        const double sign = p < 0.0 ? -1.0 : 1.0;
        fs.x(i) = sign * p;
        fs.x(i + 1) = wrapAngle(sign < 0.0 ? theta + kPi : theta);
        rotation[1 + slot] << sign,
            sign * Vector2(-normal.y(), normal.x()).dot(correction.translation()), 0.0, 1.0;
        moved[1 + slot] = 1;
        // The first estimate moves as the line, into the same coordinates.
        Vector2& first = fs.landmarks[slot].first_estimate;
        const double first_theta = first(1) + correction.theta;
        const double first_p =
            first(0) +
            Vector2(std::cos(first_theta), std::sin(first_theta)).dot(correction.translation());
        first = Vector2(sign * first_p, wrapAngle(sign < 0.0 ? first_theta + kPi : first_theta));
        break;
      }
      case LandmarkKind::kLineAngle:
        fs.x(i) = wrapAngle(fs.x(i) + correction.theta);
        fs.landmarks[slot].first_estimate(1) =
            wrapAngle(fs.landmarks[slot].first_estimate(1) + correction.theta);
        break;
    }
  }
  // P ↦ J P Jᵀ, block by block: rows of block a by R_a, columns of block b by R_bᵀ.
  // The robot's heading row/column (index 2) is not rotated.
  auto start = [&fs](int block) { return block == 0 ? 0 : fs.landmarkIndex(block - 1); };
  const int blocks = 1 + fs.landmarkCount();
  for (int a = 0; a < blocks; ++a) {
    if (!moved[a]) continue;
    const int ia = start(a);
    fs.P.block(ia, 0, 2, n) = rotation[a] * fs.P.block(ia, 0, 2, n);
  }
  for (int b = 0; b < blocks; ++b) {
    if (!moved[b]) continue;
    const int ib = start(b);
    fs.P.block(0, ib, n, 2) = fs.P.block(0, ib, n, 2) * rotation[b].transpose();
  }
  // Exactly symmetric again (the two passes round differently), in place.
  for (int c = 0; c < n; ++c) {
    for (int r = c + 1; r < n; ++r) {
      const double v = 0.5 * (fs.P(r, c) + fs.P(c, r));
      fs.P(r, c) = v;
      fs.P(c, r) = v;
    }
  }
}

}  // namespace maintenance
}  // namespace ekf_slam
