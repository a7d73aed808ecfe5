// Exhaustive correlative scan matching (Olson 2009) with a multi-level
// branch and bound (as in Hess et al. 2016), for loop closure: it finds the
// pose of a scan against a reference point set anywhere inside a search
// window of tens of metres and any heading, where ICP (a local method with a
// basin of a few decimetres) cannot start.
//
// The reference is rasterised into a likelihood grid: cell value
// L(c) = exp(−d² / 2σ²), d the distance from the cell centre to the nearest
// reference point. The score of a candidate pose T is the mean of L over the
// scan points placed by T, in [0, 1]. Level k of the grid holds, at each
// cell, the maximum of L over the 2^k × 2^k fine cells whose lower-left
// corner it is (cells outside the grid count as 0; the level extends below
// the grid so that a block starting outside it still bounds the cells it
// reaches inside), so the level-k score of a block of 2^k × 2^k translations
// bounds the fine score of every translation in the block. The search
// starts from blocks of the top level and descends depth first, best bound
// first, into the four sub-blocks of a block whose bound beats the best
// fine score found so far (or the caller's minimum score): the result is
// the exhaustive search's optimum over the window's lattice, at a cost that
// grows with the number of plausible poses rather than with the window.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

struct CorrelativeMatcherOptions {
  double resolution = 0.05;      // m: fine grid cell and translation step
  double sigma = 0.07;           // m: width of the likelihood around a reference point
  int levels = 7;                // grid levels (1: exhaustive; top blocks are 2^(levels-1) cells)
  double angular_step = 0.0087;  // rad (0.5 deg): rotation step of the search

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("resolution", resolution, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("sigma", sigma, Bounds::openClosed(0.0, 10.0, "m"));
    v.integer("levels", levels, Bounds::closed(1, 16));
    v.number("angular_step", angular_step, Bounds::openClosed(0.0, 0.5, "rad"));
  }

  std::string validate() const;  // empty when valid, else names the bad field
};

// The likelihood field of a reference point set, with its bounding levels.
class LikelihoodGrid {
 public:
  // Larger point sets (kilometres across: corrupt poses) give an empty grid.
  static constexpr double kMaxCells = 2.5e7;

  LikelihoodGrid() = default;  // empty
  LikelihoodGrid(const std::vector<Vector2>& points, const CorrelativeMatcherOptions& options);

  // Rebuilds the grid for `points` in the storage of the previous one: a
  // caller that builds grid after grid (the loop closer, one per verified
  // candidate) then reuses its buffers instead of allocating megabytes each
  // time, which costs page faults and fragments the heap of a long-running
  // thread. The result equals a grid constructed from the same arguments.
  void build(const std::vector<Vector2>& points, const CorrelativeMatcherOptions& options);
  // Bytes the grid's buffers hold (capacity, not size).
  size_t storageBytes() const;
  // Hands the buffers back (the grid is then empty).
  void release();

  // Fine cell of a point (may lie outside the grid).
  void cellOf(const Vector2& p, int* ix, int* iy) const;
  // Level 0 is the likelihood itself; level k bounds it over 2^k × 2^k cells.
  float value(int level, int ix, int iy) const {
    const int pad = pad_[level];
    const int x = ix + pad, y = iy + pad, w = width_ + pad;
    if (x < 0 || y < 0 || x >= w || y >= height_ + pad) return 0.0f;
    return levels_[level][static_cast<size_t>(y) * w + x];
  }
  float fine(int ix, int iy) const { return value(0, ix, iy); }
  int levels() const { return level_count_; }
  double resolution() const { return resolution_; }
  bool empty() const { return width_ == 0; }
  // Corners of the grid (m, in the points' frame).
  Vector2 lowerCorner() const { return origin_; }
  Vector2 upperCorner() const { return origin_ + resolution_ * Vector2(width_, height_); }

 private:
  bool inside(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width_ && iy < height_; }
  size_t index(int ix, int iy) const { return static_cast<size_t>(iy) * width_ + ix; }

  double resolution_ = 0.05;
  Vector2 origin_ = Vector2::Zero();  // corner of cell (0, 0)
  int width_ = 0;
  int height_ = 0;
  int level_count_ = 0;                     // levels in use; levels_ may hold more buffers
  std::vector<std::vector<float>> levels_;  // level k: (width + pad_[k]) × (height + pad_[k])
  std::vector<int> pad_;                    // cells level k extends below the grid's lower edges
  // build's scratch: each fine cell's squared distance to its nearest
  // point, and a level's maxima along x
  std::vector<double> scratch_;
  std::vector<float> along_x_;
};

struct CorrelativeResult {
  Pose2 pose;          // best pose of the points' frame in the grid's frame
  double score = 0.0;  // mean likelihood of the points at that pose, [0, 1]
};

// Searches x, y within ±linear_window of the guess and θ within
// ±angular_window (at most a full turn), on the grid's lattice.
// Translations that would leave every point outside the grid cannot score
// and are not searched, so a window far larger than the grid costs little.
// With min_score > 0 only poses scoring above it are looked for: the
// result is the best of those, or score 0 at the guess when there is none
// (much faster when most of the window cannot reach min_score).
CorrelativeResult correlativeSearch(const std::vector<Vector2>& points, const LikelihoodGrid& grid,
                                    const Pose2& guess, double linear_window, double angular_window,
                                    const CorrelativeMatcherOptions& options,
                                    double min_score = 0.0);

// The same search with the translations within distinct_radius of `best`
// left out (at every heading): the best pose of the window at another
// place. A place whose runner-up scores nearly as well as its best is
// ambiguous (a corridor whose doors repeat, two rooms alike): Olson's
// uniqueness test for loop closures. Score 0 when no pose there beats
// min_score.
CorrelativeResult correlativeRunnerUp(const std::vector<Vector2>& points,
                                      const LikelihoodGrid& grid, const Pose2& guess,
                                      double linear_window, double angular_window,
                                      const CorrelativeMatcherOptions& options, const Pose2& best,
                                      double distinct_radius, double min_score);

// Keeps the first point in each cell of a `spacing` grid (all of them when
// spacing is not positive): scans of one place merged do not pile up.
std::vector<Vector2> gridThinned(const std::vector<Vector2>& points, double spacing);

}  // namespace ekf_slam
