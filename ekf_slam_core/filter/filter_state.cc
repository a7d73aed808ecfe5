#include "ekf_slam_core/filter/filter_state.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace ekf_slam {

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

bool isValidCovariance2(const Matrix2& c) {
  return c.allFinite() && std::abs(c(0, 1) - c(1, 0)) <= 1e-9 * (1.0 + c.cwiseAbs().maxCoeff()) &&
         c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0;
}

FilterStatus factorInnovation(Eigen::MatrixXd* S, Eigen::LLT<Eigen::MatrixXd>* llt) {
  *S = 0.5 * (*S + S->transpose()).eval();
  if (!S->allFinite()) return FilterStatus::kNonFiniteInput;
  llt->compute(*S);
  if (llt->info() != Eigen::Success || !(llt->matrixLLT().diagonal().minCoeff() > 0.0)) {
    return FilterStatus::kSingularInnovation;
  }
  return FilterStatus::kOk;
}

FilterState::FilterState(const Pose2& initial_pose, const Matrix3& initial_covariance) {
  reserve(64);
  x.head<3>() = initial_pose.vector();
  P.topLeftCorner<3, 3>() = 0.5 * (initial_covariance + initial_covariance.transpose());
}

void FilterState::reserve(int needed) {
  if (x.size() >= needed) return;
  const int capacity = std::max(needed, static_cast<int>(2 * x.size()));
  Eigen::VectorXd grown_x = Eigen::VectorXd::Zero(capacity);
  Eigen::MatrixXd grown_P = Eigen::MatrixXd::Zero(capacity, capacity);
  if (x.size() > 0) {
    grown_x.head(dim) = x.head(dim);
    grown_P.topLeftCorner(dim, dim) = P.topLeftCorner(dim, dim);
  }
  x.swap(grown_x);
  P.swap(grown_P);
}

int FilterState::slotOf(int id) const {
  const auto it = slot_of_id.find(id);
  return it == slot_of_id.end() ? -1 : it->second;
}

void FilterState::applyGain(const Eigen::MatrixXd& PHt, const Eigen::LLT<Eigen::MatrixXd>& llt,
                            const Eigen::VectorXd& innovation) {
  // With S = L Lᵀ and W = P Hᵀ L⁻ᵀ:  x += W L⁻¹ ν,  P −= W Wᵀ.
  const int n = dim;
  const Eigen::MatrixXd Wt = llt.matrixL().solve(PHt.transpose());  // rows of ν × n
  const Eigen::VectorXd whitened = llt.matrixL().solve(innovation);
  x.head(n).noalias() += Wt.transpose() * whitened;
  x(2) = wrapAngle(x(2));
  P.topLeftCorner(n, n).selfadjointView<Eigen::Lower>().rankUpdate(Wt.transpose(), -1.0);
}

void FilterState::mirrorPoseRowsAndLandmarkBlocks() {
  // After a downdate of the lower triangle, O(n): the upper triangle of the
  // pose rows and of each landmark's 2 × 2 block, which the predictions read.
  const int n = dim;
  P(0, 1) = P(1, 0);
  P(0, 2) = P(2, 0);
  P(1, 2) = P(2, 1);
  P.block(0, kPoseDim, kPoseDim, n - kPoseDim) =
      P.block(kPoseDim, 0, n - kPoseDim, kPoseDim).transpose();
  for (const LandmarkInfo& info : landmarks) {
    if (landmarkDim(info.kind) == 2) P(info.index, info.index + 1) = P(info.index + 1, info.index);
  }
}

void FilterState::fillLandmarkColumns(const std::vector<int>& slots) {
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
      const int dim = landmarkDim(landmarks[slot].kind);
      const int count = std::min(c0 + kTile, j) - c0;
      if (count <= 0) continue;
      P.block(c0, j, count, dim) = P.block(j, c0, dim, count).transpose();
    }
  }
}

Eigen::MatrixXd FilterState::covariance() const {
  return P.topLeftCorner(dim, dim).selfadjointView<Eigen::Lower>();
}

Matrix2 FilterState::landmarkCrossCovariance(int slot_a, int slot_b) const {
  const int ja = landmarkIndex(slot_a), jb = landmarkIndex(slot_b);
  if (ja >= jb) return P.block<2, 2>(ja, jb);
  return P.block<2, 2>(jb, ja).transpose();
}

int FilterState::appendLandmark(LandmarkKind kind, int id, int observations,
                                const Vector2& first_estimate) {
  LandmarkInfo info;
  info.id = id;
  info.kind = kind;
  info.index = dim;
  info.first_estimate = first_estimate;
  info.observations = std::max(1, observations);
  info.created_step = step;
  info.last_seen_step = step;
  dim += landmarkDim(kind);
  slot_of_id[id] = landmarkCount();
  landmarks.push_back(info);
  next_id = std::max(next_id, id + 1);
  return id;
}

void FilterState::removeSlots(const std::vector<int>& slots) {
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
    const int dim = landmarkDim(landmarks[s].kind);
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
  double* const mean = x.data();
  for (const Run& rows : runs) {
    if (rows.from != rows.to) {
      std::copy(mean + rows.from, mean + rows.from + rows.length, mean + rows.to);
    }
  }
  for (const Run& cols : runs) {
    for (int k = 0; k < cols.length; ++k) {
      const int c = cols.to + k;
      const double* const from = &P(0, cols.from + k);
      double* const to = &P(0, c);
      for (const Run& rows : runs) {
        if (cols.from == cols.to && rows.from == rows.to) continue;
        // Rows [to + skip, to + length) of this run are needed in column c.
        const int skip = rows.to == 0 ? 0 : std::max(0, c - 1 - rows.to);
        if (skip >= rows.length) continue;
        std::copy(from + rows.from + skip, from + rows.from + rows.length, to + rows.to + skip);
      }
    }
  }
  dim = n;

  int kept = 0, index = kPoseDim;
  for (int s = 0; s < static_cast<int>(drop.size()); ++s) {
    if (drop[s]) {
      slot_of_id.erase(landmarks[s].id);
      continue;
    }
    if (kept != s) {
      landmarks[kept] = landmarks[s];
      slot_of_id[landmarks[kept].id] = kept;
    }
    landmarks[kept].index = index;
    index += landmarkDim(landmarks[kept].kind);
    ++kept;
  }
  landmarks.resize(kept);
}

}  // namespace ekf_slam
