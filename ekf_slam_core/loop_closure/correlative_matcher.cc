#include "ekf_slam_core/loop_closure/correlative_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <unordered_set>

namespace ekf_slam {

std::string CorrelativeMatcherOptions::validate() const { return checkFields(*this); }

LikelihoodGrid::LikelihoodGrid(const std::vector<Vector2>& points,
                               const CorrelativeMatcherOptions& options) {
  build(points, options);
}

void LikelihoodGrid::build(const std::vector<Vector2>& points,
                           const CorrelativeMatcherOptions& options) {
  resolution_ = options.resolution;
  origin_ = Vector2::Zero();
  width_ = height_ = level_count_ = 0;
  pad_.assign(1, 0);
  if (points.empty()) return;
  // The likelihood is cut at 3 sigma, beyond which it is below 1 %.
  const double reach = 3.0 * options.sigma;
  Vector2 low = points.front(), high = points.front();
  for (const Vector2& p : points) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  origin_ = low - Vector2::Constant(reach + resolution_);
  const double cells_x = std::ceil((high.x() - origin_.x() + reach) / resolution_) + 2.0;
  const double cells_y = std::ceil((high.y() - origin_.y() + reach) / resolution_) + 2.0;
  // A submap kilometres across is corrupt input, not a place: no grid (the
  // search then finds nothing) rather than an unbounded allocation.
  if (!(cells_x * cells_y <= kMaxCells)) return;
  width_ = static_cast<int>(cells_x);
  height_ = static_cast<int>(cells_y);
  const size_t cells_total = static_cast<size_t>(width_) * height_;
  // assign() keeps a buffer's capacity: a grid no larger than an earlier
  // one allocates nothing.
  if (levels_.size() < static_cast<size_t>(options.levels)) levels_.resize(options.levels);
  level_count_ = 1;
  // Each cell's value is exp(−d²/2σ²) for its nearest point: exp falls as
  // d² grows, so the nearest point's squared distance is found first and
  // exp taken once per cell, not once per point and cell (the same floats:
  // the maximum of the values is the value of the minimum).
  const int cells = static_cast<int>(std::ceil(reach / resolution_));
  const double inv_two_sigma2 = 1.0 / (2.0 * options.sigma * options.sigma);
  constexpr double kNone = std::numeric_limits<double>::infinity();
  std::vector<double>& nearest_d2 = scratch_;
  nearest_d2.assign(cells_total, kNone);
  for (const Vector2& p : points) {
    int cx, cy;
    cellOf(p, &cx, &cy);
    for (int iy = cy - cells; iy <= cy + cells; ++iy) {
      for (int ix = cx - cells; ix <= cx + cells; ++ix) {
        if (!inside(ix, iy)) continue;
        const Vector2 centre = origin_ + resolution_ * Vector2(ix + 0.5, iy + 0.5);
        double& d2 = nearest_d2[index(ix, iy)];
        d2 = std::min(d2, (centre - p).squaredNorm());
      }
    }
  }
  std::vector<float>& fine = levels_[0];
  fine.assign(cells_total, 0.0f);
  for (size_t i = 0; i < cells_total; ++i) {
    if (nearest_d2[i] != kNone) {
      fine[i] = static_cast<float>(std::exp(-nearest_d2[i] * inv_two_sigma2));
    }
  }
  // Level k from level k-1: the maximum over [i, i + 2^k) is the larger of
  // the maxima over [i, i + h) and [i + h, i + 2h), h = 2^(k-1); first
  // along x, then along y. A block that starts outside the grid may still
  // reach into it, so level k extends 2^k - 1 cells beyond the grid's lower
  // edges (pad_[k]); cells beyond it are 0 at every level.
  for (int k = 1; k < options.levels; ++k) {
    const int h = 1 << (k - 1);
    const std::vector<float>& previous = levels_[k - 1];
    const int previous_width = width_ + pad_.back();
    const int pad = pad_.back() + h;
    const int w = width_ + pad, ht = height_ + pad;
    // Row y, column x of the maxima along x holds the larger of the previous
    // level's cells (x − h, y − h) and (x, y − h) in its own indices, 0
    // outside it: the first h rows lie wholly outside.
    std::vector<float>& along_x = along_x_;
    along_x.assign(static_cast<size_t>(w) * ht, 0.0f);
    for (int y = h; y < ht; ++y) {
      const float* in = previous.data() + static_cast<size_t>(y - h) * previous_width;
      float* out = along_x.data() + static_cast<size_t>(y) * w;
      for (int x = 0; x < w; ++x) {
        const float left = x >= h && x - h < previous_width ? in[x - h] : 0.0f;
        const float right = x < previous_width ? in[x] : 0.0f;
        out[x] = std::max(left, right);
      }
    }
    std::vector<float>& level = levels_[k];
    level.assign(along_x.size(), 0.0f);
    for (int y = 0; y < ht; ++y) {
      const float* row = along_x.data() + static_cast<size_t>(y) * w;
      float* out = level.data() + static_cast<size_t>(y) * w;
      if (y + h < ht) {
        const float* above = row + static_cast<size_t>(h) * w;
        for (int x = 0; x < w; ++x) out[x] = std::max(row[x], above[x]);
      } else {
        std::copy(row, row + w, out);
      }
    }
    pad_.push_back(pad);
    level_count_ = k + 1;
  }
}

size_t LikelihoodGrid::storageBytes() const {
  size_t bytes = scratch_.capacity() * sizeof(double) + along_x_.capacity() * sizeof(float);
  for (const std::vector<float>& level : levels_) bytes += level.capacity() * sizeof(float);
  return bytes;
}

void LikelihoodGrid::release() { *this = LikelihoodGrid(); }

void LikelihoodGrid::cellOf(const Vector2& p, int* ix, int* iy) const {
  *ix = static_cast<int>(std::floor((p.x() - origin_.x()) / resolution_));
  *iy = static_cast<int>(std::floor((p.y() - origin_.y()) / resolution_));
}

namespace {

struct Candidate {
  double score;  // at its level: a bound on every translation of the block
  int rotation;  // index into the rotations
  int i, j;      // first translation offset of the block (cells)
};

class Search {
 public:
  Search(const LikelihoodGrid& grid, const std::vector<std::vector<std::pair<int, int>>>& cells,
         int i_max, int j_max, double inv_count)
      : grid_(grid), cells_(cells), i_max_(i_max), j_max_(j_max), inv_count_(inv_count) {}

  // Translations within `radius` cells of offset (i, j) are left out of
  // the search (every rotation): the runner-up search.
  void exclude(int i, int j, double radius) {
    excluded_ = true;
    ex_i_ = i;
    ex_j_ = j;
    ex_r2_ = radius * radius;
  }
  // Every translation of the block (size × size offsets from c) excluded.
  bool excluded(const Candidate& c, int size) const {
    if (!excluded_) return false;
    // The block's farthest corner from the excluded centre.
    const double di = std::max(std::abs(c.i - ex_i_), std::abs(c.i + size - 1 - ex_i_));
    const double dj = std::max(std::abs(c.j - ex_j_), std::abs(c.j + size - 1 - ex_j_));
    return di * di + dj * dj <= ex_r2_;
  }

  double score(int level, const Candidate& c) const {
    double sum = 0.0;
    for (const auto& [ix, iy] : cells_[c.rotation]) sum += grid_.value(level, ix + c.i, iy + c.j);
    return sum * inv_count_;
  }

  // Depth first into a block of `level` whose bound beats the best so far.
  void descend(int level, const Candidate& block, Candidate* best) const {
    if (excluded(block, 1 << level)) return;
    if (level == 0) {
      if (block.score > best->score) *best = block;
      return;
    }
    const int h = 1 << (level - 1);
    Candidate children[4];
    int n = 0;
    for (int di = 0; di < 2; ++di) {
      for (int dj = 0; dj < 2; ++dj) {
        Candidate c{0.0, block.rotation, block.i + di * h, block.j + dj * h};
        if (c.i > i_max_ || c.j > j_max_) continue;
        c.score = score(level - 1, c);
        children[n++] = c;
      }
    }
    // Best first (insertion sort of at most four).
    for (int a = 1; a < n; ++a) {
      for (int b = a; b > 0 && children[b].score > children[b - 1].score; --b) {
        std::swap(children[b], children[b - 1]);
      }
    }
    for (int k = 0; k < n; ++k) {
      if (children[k].score <= best->score) break;
      descend(level - 1, children[k], best);
    }
  }

 private:
  const LikelihoodGrid& grid_;
  const std::vector<std::vector<std::pair<int, int>>>& cells_;
  int i_max_, j_max_;
  double inv_count_;
  bool excluded_ = false;
  int ex_i_ = 0, ex_j_ = 0;
  double ex_r2_ = 0.0;
};

}  // namespace

namespace {

// The search of both entry points; with `exclusion`, translations within
// `exclusion_radius` of its position are not searched.
CorrelativeResult searchWindow(const std::vector<Vector2>& points, const LikelihoodGrid& grid,
                               const Pose2& guess, double linear_window, double angular_window,
                               const CorrelativeMatcherOptions& options, double min_score,
                               const Pose2* exclusion, double exclusion_radius) {
  CorrelativeResult result;
  result.pose = guess;
  if (points.empty() || grid.empty()) return result;
  const double res = grid.resolution();
  const int n = static_cast<int>(std::ceil(linear_window / res));
  // Rotations: ±m steps, no more than one full turn.
  const int full_turn = static_cast<int>(std::floor(2.0 * kPi / options.angular_step));
  const int m =
      std::min(static_cast<int>(std::ceil(angular_window / options.angular_step)), full_turn / 2);
  const int rotations = 2 * m + 1;
  const int count = static_cast<int>(points.size());

  // Translations that keep some point on the grid: the points' origin no
  // farther outside the grid than the farthest point reaches.
  double reach = 0.0;
  for (const Vector2& p : points) reach = std::max(reach, p.norm());
  const Vector2 low = grid.lowerCorner() - Vector2::Constant(reach + res);
  const Vector2 high = grid.upperCorner() + Vector2::Constant(reach + res);
  const int i_min = std::max(-n, static_cast<int>(std::floor((low.x() - guess.x) / res)));
  const int i_max = std::min(n, static_cast<int>(std::ceil((high.x() - guess.x) / res)));
  const int j_min = std::max(-n, static_cast<int>(std::floor((low.y() - guess.y) / res)));
  const int j_max = std::min(n, static_cast<int>(std::ceil((high.y() - guess.y) / res)));
  if (i_min > i_max || j_min > j_max) return result;

  // Cells of the points at every rotation, before any translation offset.
  std::vector<std::vector<std::pair<int, int>>> cells(rotations);
  for (int r = 0; r < rotations; ++r) {
    const Pose2 rotated(guess.x, guess.y, guess.theta + (r - m) * options.angular_step);
    cells[r].reserve(count);
    for (const Vector2& p : points) {
      int ix, iy;
      grid.cellOf(transformFrom(rotated, p), &ix, &iy);
      cells[r].emplace_back(ix, iy);
    }
  }
  Search search(grid, cells, i_max, j_max, 1.0 / count);
  if (exclusion != nullptr) {
    search.exclude(static_cast<int>(std::lround((exclusion->x - guess.x) / res)),
                   static_cast<int>(std::lround((exclusion->y - guess.y) / res)),
                   exclusion_radius / res);
  }
  const int top = grid.levels() - 1;
  const int step = 1 << top;
  std::vector<Candidate> blocks;
  for (int r = 0; r < rotations; ++r) {
    for (int i = i_min; i <= i_max; i += step) {
      for (int j = j_min; j <= j_max; j += step) {
        Candidate c{0.0, r, i, j};
        if (search.excluded(c, step)) continue;
        c.score = search.score(top, c);
        if (c.score > min_score) blocks.push_back(c);
      }
    }
  }
  std::sort(blocks.begin(), blocks.end(),
            [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  Candidate best{min_score, -1, 0, 0};

  for (const Candidate& block : blocks) {
    if (block.score <= best.score) break;  // nothing left can do better
    search.descend(top, block, &best);
  }
  if (best.rotation < 0) return result;  // nothing above min_score
  result.score = best.score;
  result.pose = Pose2(guess.x + best.i * res, guess.y + best.j * res,
                      wrapAngle(guess.theta + (best.rotation - m) * options.angular_step));
  return result;
}

}  // namespace

CorrelativeResult correlativeSearch(const std::vector<Vector2>& points, const LikelihoodGrid& grid,
                                    const Pose2& guess, double linear_window, double angular_window,
                                    const CorrelativeMatcherOptions& options, double min_score) {
  return searchWindow(points, grid, guess, linear_window, angular_window, options, min_score,
                      nullptr, 0.0);
}

CorrelativeResult correlativeRunnerUp(const std::vector<Vector2>& points,
                                      const LikelihoodGrid& grid, const Pose2& guess,
                                      double linear_window, double angular_window,
                                      const CorrelativeMatcherOptions& options, const Pose2& best,
                                      double distinct_radius, double min_score) {
  return searchWindow(points, grid, guess, linear_window, angular_window, options, min_score, &best,
                      distinct_radius);
}

std::vector<Vector2> gridThinned(const std::vector<Vector2>& points, double spacing) {
  if (!(spacing > 0.0)) return points;
  std::vector<Vector2> out;
  std::unordered_set<unsigned long long> seen;
  for (const Vector2& p : points) {
    // Cell indices packed into one key (shifted as unsigned: shifting a
    // negative signed value is undefined).
    const auto ix =
        static_cast<unsigned long long>(static_cast<long long>(std::floor(p.x() / spacing)));
    const auto iy =
        static_cast<unsigned long long>(static_cast<long long>(std::floor(p.y() / spacing)));
    if (seen.insert((ix << 32) ^ (iy & 0xffffffffULL)).second) out.push_back(p);
  }
  return out;
}

}  // namespace ekf_slam
