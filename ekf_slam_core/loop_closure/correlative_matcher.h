// Exhaustive correlative scan matching (Olson 2009) with a two-level
// branch-and-bound, for loop closure: it finds the pose of a scan against a
// reference point set anywhere inside a search window of metres and tens of
// degrees, where ICP (a local method with a basin of a few decimetres)
// cannot start.
//
// The reference is rasterised into a likelihood grid: cell value
// L(c) = exp(−d² / 2σ²), d the distance from the cell centre to the nearest
// reference point. The score of a candidate pose T is the mean of L over the
// scan points placed by T, in [0, 1]. A coarse grid holds, at each cell, the
// maximum of L over the f × f fine cells whose lower-left corner it is, so
// the coarse score of a block of f × f translations bounds the fine score of
// every translation in the block. Blocks are refined best bound first, and
// the search stops when no remaining bound beats the best fine score: the
// result is the exhaustive search's optimum over the window's lattice.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

struct CorrelativeMatcherOptions {
  double resolution = 0.05;      // m: fine grid cell and translation step
  double sigma = 0.07;           // m: width of the likelihood around a reference point
  int coarse_factor = 8;         // fine cells per coarse block side
  double angular_step = 0.0087;  // rad (0.5 deg): rotation step of the search

  std::string validate() const;  // empty when valid, else names the bad field
};

// The likelihood field of a reference point set, with its coarse bound.
class LikelihoodGrid {
 public:
  LikelihoodGrid(const std::vector<Vector2>& points, const CorrelativeMatcherOptions& options);

  // Fine cell of a point (may lie outside the grid).
  void cellOf(const Vector2& p, int* ix, int* iy) const;
  float fine(int ix, int iy) const { return inside(ix, iy) ? fine_[index(ix, iy)] : 0.0f; }
  float coarse(int ix, int iy) const { return inside(ix, iy) ? coarse_[index(ix, iy)] : 0.0f; }
  double resolution() const { return resolution_; }
  int coarseFactor() const { return factor_; }

 private:
  bool inside(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width_ && iy < height_; }
  size_t index(int ix, int iy) const { return static_cast<size_t>(iy) * width_ + ix; }

  double resolution_;
  int factor_;
  Vector2 origin_ = Vector2::Zero();  // corner of cell (0, 0)
  int width_ = 0;
  int height_ = 0;
  std::vector<float> fine_;
  std::vector<float> coarse_;
};

struct CorrelativeResult {
  Pose2 pose;          // best pose of the points' frame in the grid's frame
  double score = 0.0;  // mean likelihood of the points at that pose, [0, 1]
};

// Searches x, y within ±linear_window of the guess and θ within
// ±angular_window, on the grid's lattice.
CorrelativeResult correlativeSearch(const std::vector<Vector2>& points, const LikelihoodGrid& grid,
                                    const Pose2& guess, double linear_window, double angular_window,
                                    const CorrelativeMatcherOptions& options);

}  // namespace ekf_slam
