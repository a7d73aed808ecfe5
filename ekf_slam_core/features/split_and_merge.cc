#include "ekf_slam_core/features/split_and_merge.h"

#include <algorithm>
#include <cmath>

#include "ekf_slam_core/features/line_fit.h"

namespace ekf_slam {
namespace {

// Index and distance of the point of points[first+1 .. last-1] farthest from
// the chord points[first] → points[last] (from points[first] if they coincide).
std::pair<int, double> farthestFromChord(const std::vector<ScanPoint>& points, int first,
                                         int last) {
  const Vector2 a = points[first].xy;
  const Vector2 chord = points[last].xy - a;
  const double length = chord.norm();
  int best = -1;
  double best_distance = -1.0;
  for (int i = first + 1; i < last; ++i) {
    const Vector2 q = points[i].xy - a;
    const double distance =
        length > 0.0 ? std::abs(chord.x() * q.y() - chord.y() * q.x()) / length : q.norm();
    if (distance > best_distance) {
      best_distance = distance;
      best = i;
    }
  }
  return {best, best_distance};
}

bool piecesAgree(const std::vector<ScanPoint>& points, const IndexSpan& a, const IndexSpan& b,
                 const FeatureOptions& options) {
  LineFit fit_a, fit_b, joined;
  if (!fitLineGeometry(points, a.first, b.last, &joined) ||
      joined.max_residual > options.split_threshold) {
    return false;
  }
  // A two-point piece has no direction of its own to compare: the residual
  // test decides.
  if (a.size() < 3 || b.size() < 3) return true;
  if (!fitLine(points, a.first, a.last, options.range_sigma, options.bearing_sigma, &fit_a) ||
      !fitLine(points, b.first, b.last, options.range_sigma, options.bearing_sigma, &fit_b)) {
    return false;
  }
  // Compare in the joined line's orientation so that a θ flip of ±π with p
  // near 0 does not look like a difference.
  const auto aligned = [&](const LineFit& f) {
    return std::cos(f.theta - joined.theta) >= 0.0 ? Vector2(f.p, f.theta)
                                                   : Vector2(-f.p, f.theta + kPi);
  };
  const Vector2 va = aligned(fit_a), vb = aligned(fit_b);
  const Vector2 difference(va(0) - vb(0), wrapAngle(va(1) - vb(1)));
  const Matrix2 covariance = fit_a.covariance + fit_b.covariance;
  const double det = covariance(0, 0) * covariance(1, 1) - covariance(0, 1) * covariance(1, 0);
  if (!(det > 0.0)) return false;
  Matrix2 inverse;
  inverse << covariance(1, 1), -covariance(0, 1), -covariance(1, 0), covariance(0, 0);
  inverse /= det;
  return difference.dot(inverse * difference) < options.merge_chi2;
}

}  // namespace

std::vector<IndexSpan> splitAndMerge(const std::vector<ScanPoint>& points, const IndexSpan& cluster,
                                     const FeatureOptions& options) {
  std::vector<IndexSpan> pieces;
  if (cluster.size() < 3) {
    pieces.push_back(cluster);
    return pieces;
  }
  // Split: iterative depth-first, left piece first, so `pieces` ends up in
  // scan order.
  std::vector<IndexSpan> stack = {cluster};
  while (!stack.empty()) {
    const IndexSpan span = stack.back();
    stack.pop_back();
    if (span.size() >= 3) {
      const auto [split, distance] = farthestFromChord(points, span.first, span.last);
      if (distance > options.split_threshold) {
        stack.push_back({split, span.last});
        stack.push_back({span.first, split});
        continue;
      }
    }
    pieces.push_back(span);
  }
  // Merge: a chord-based split can cut a noisy straight wall. Undo it when
  // the two pieces' fitted lines agree within their covariances (squared
  // Mahalanobis distance of (Δp, Δθ) below options.merge_chi2) and one line
  // fits the union within hf. A residual test alone would glue the first few
  // readings of a short adjacent face onto a wall and tilt it.
  std::vector<IndexSpan> merged;
  merged.reserve(pieces.size());
  for (const IndexSpan& piece : pieces) {
    if (!merged.empty() && piecesAgree(points, merged.back(), piece, options)) {
      merged.back().last = piece.last;
      continue;
    }
    merged.push_back(piece);
  }
  return merged;
}

}  // namespace ekf_slam
