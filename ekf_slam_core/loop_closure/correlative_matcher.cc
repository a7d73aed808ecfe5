#include "ekf_slam_core/loop_closure/correlative_matcher.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {

std::string CorrelativeMatcherOptions::validate() const {
  if (!(resolution > 0.0)) return "resolution must be > 0 (m)";
  if (!(sigma > 0.0)) return "sigma must be > 0 (m)";
  if (coarse_factor < 1) return "coarse_factor must be >= 1";
  if (!(angular_step > 0.0)) return "angular_step must be > 0 (rad)";
  return "";
}

LikelihoodGrid::LikelihoodGrid(const std::vector<Vector2>& points,
                               const CorrelativeMatcherOptions& options)
    : resolution_(options.resolution), factor_(options.coarse_factor) {
  if (points.empty()) return;
  // The likelihood is cut at 3 sigma, beyond which it is below 1 %.
  const double reach = 3.0 * options.sigma;
  Vector2 low = points.front(), high = points.front();
  for (const Vector2& p : points) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  origin_ = low - Vector2::Constant(reach + resolution_);
  width_ = static_cast<int>(std::ceil((high.x() - origin_.x() + reach) / resolution_)) + 2;
  height_ = static_cast<int>(std::ceil((high.y() - origin_.y() + reach) / resolution_)) + 2;
  fine_.assign(static_cast<size_t>(width_) * height_, 0.0f);
  const int cells = static_cast<int>(std::ceil(reach / resolution_));
  const double inv_two_sigma2 = 1.0 / (2.0 * options.sigma * options.sigma);
  for (const Vector2& p : points) {
    int cx, cy;
    cellOf(p, &cx, &cy);
    for (int iy = cy - cells; iy <= cy + cells; ++iy) {
      for (int ix = cx - cells; ix <= cx + cells; ++ix) {
        if (!inside(ix, iy)) continue;
        const Vector2 centre = origin_ + resolution_ * Vector2(ix + 0.5, iy + 0.5);
        const float value =
            static_cast<float>(std::exp(-(centre - p).squaredNorm() * inv_two_sigma2));
        float& cell = fine_[index(ix, iy)];
        cell = std::max(cell, value);
      }
    }
  }
  // Coarse bound: running maximum over [ix, ix + f) along x, then along y.
  std::vector<float> along_x(fine_.size(), 0.0f);
  for (int iy = 0; iy < height_; ++iy) {
    for (int ix = 0; ix < width_; ++ix) {
      float m = 0.0f;
      for (int k = 0; k < factor_ && ix + k < width_; ++k)
        m = std::max(m, fine_[index(ix + k, iy)]);
      along_x[index(ix, iy)] = m;
    }
  }
  coarse_.assign(fine_.size(), 0.0f);
  for (int iy = 0; iy < height_; ++iy) {
    for (int ix = 0; ix < width_; ++ix) {
      float m = 0.0f;
      for (int k = 0; k < factor_ && iy + k < height_; ++k) {
        m = std::max(m, along_x[index(ix, iy + k)]);
      }
      coarse_[index(ix, iy)] = m;
    }
  }
}

void LikelihoodGrid::cellOf(const Vector2& p, int* ix, int* iy) const {
  *ix = static_cast<int>(std::floor((p.x() - origin_.x()) / resolution_));
  *iy = static_cast<int>(std::floor((p.y() - origin_.y()) / resolution_));
}

namespace {

struct Block {
  double bound;  // coarse score: no translation in the block scores higher
  int rotation;  // index into the rotations
  int i0, j0;    // first translation offset of the block (cells)
};

}  // namespace

CorrelativeResult correlativeSearch(const std::vector<Vector2>& points, const LikelihoodGrid& grid,
                                    const Pose2& guess, double linear_window, double angular_window,
                                    const CorrelativeMatcherOptions& options) {
  CorrelativeResult best;
  best.pose = guess;
  if (points.empty()) return best;
  const double res = grid.resolution();
  const int f = grid.coarseFactor();
  const int n = static_cast<int>(std::ceil(linear_window / res));
  const int m = static_cast<int>(std::ceil(angular_window / options.angular_step));
  const int rotations = 2 * m + 1;
  const int count = static_cast<int>(points.size());
  const double inv_count = 1.0 / count;

  // Cells of the points at every rotation, before any translation offset.
  std::vector<std::vector<std::pair<int, int>>> cells(rotations);
  std::vector<Block> blocks;
  for (int r = 0; r < rotations; ++r) {
    const double theta = guess.theta + (r - m) * options.angular_step;
    const Pose2 rotated(guess.x, guess.y, theta);
    cells[r].reserve(count);
    for (const Vector2& p : points) {
      int ix, iy;
      grid.cellOf(transformFrom(rotated, p), &ix, &iy);
      cells[r].emplace_back(ix, iy);
    }
    for (int i0 = -n; i0 <= n; i0 += f) {
      for (int j0 = -n; j0 <= n; j0 += f) {
        double sum = 0.0;
        for (const auto& [ix, iy] : cells[r]) sum += grid.coarse(ix + i0, iy + j0);
        blocks.push_back({sum * inv_count, r, i0, j0});
      }
    }
  }
  std::sort(blocks.begin(), blocks.end(),
            [](const Block& a, const Block& b) { return a.bound > b.bound; });

  int best_r = m, best_i = 0, best_j = 0;
  for (const Block& block : blocks) {
    if (block.bound <= best.score) break;  // nothing left can do better
    for (int i = block.i0; i < block.i0 + f && i <= n; ++i) {
      for (int j = block.j0; j < block.j0 + f && j <= n; ++j) {
        double sum = 0.0;
        for (const auto& [ix, iy] : cells[block.rotation]) sum += grid.fine(ix + i, iy + j);
        if (sum * inv_count > best.score) {
          best.score = sum * inv_count;
          best_r = block.rotation;
          best_i = i;
          best_j = j;
        }
      }
    }
  }
  best.pose = Pose2(guess.x + best_i * res, guess.y + best_j * res,
                    guess.theta + (best_r - m) * options.angular_step);
  return best;
}

}  // namespace ekf_slam
