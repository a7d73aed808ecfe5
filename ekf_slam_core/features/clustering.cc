#include "ekf_slam_core/features/clustering.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ekf_slam {

std::vector<ScanPoint> scanToPoints(const Scan& scan) {
  std::vector<ScanPoint> points;
  points.reserve(scan.ranges.size());
  for (int i = 0; i < scan.size(); ++i) {
    if (!scan.isValid(i)) continue;
    ScanPoint p;
    p.beam = i;
    p.range = scan.ranges[i];
    p.bearing = scan.angle(i);
    p.xy = Vector2(p.range * std::cos(p.bearing), p.range * std::sin(p.bearing));
    points.push_back(p);
  }
  return points;
}

double clusterGapThreshold(const ScanPoint& a, const ScanPoint& b, const FeatureOptions& options) {
  if (options.cluster_mode == ClusterMode::kFixed) return options.cluster_threshold;
  // A surface seen at incidence λ between two beams Δφ apart leaves a gap of
  // r sinΔφ / sin(λ − Δφ) (law of sines in the triangle laser, a, b); a wider
  // gap means a steeper surface than λ, i.e. a different object.
  const double delta = std::abs(b.bearing - a.bearing);
  const double lambda = options.cluster_incidence_angle;
  if (delta >= lambda) return options.cluster_threshold;
  const double adaptive =
      a.range * std::sin(delta) / std::sin(lambda - delta) + 3.0 * options.range_sigma;
  return std::max(options.cluster_threshold, adaptive);
}

std::vector<IndexSpan> clusterPoints(const std::vector<ScanPoint>& points,
                                     const FeatureOptions& options) {
  std::vector<IndexSpan> clusters;
  if (points.empty()) return clusters;
  IndexSpan current{0, 0};
  for (int i = 1; i < static_cast<int>(points.size()); ++i) {
    const ScanPoint& a = points[i - 1];
    const ScanPoint& b = points[i];
    const int invalid_between = std::abs(b.beam - a.beam) - 1;
    const bool split = invalid_between > options.cluster_max_invalid_beams ||
                       (b.xy - a.xy).norm() > clusterGapThreshold(a, b, options);
    if (split) {
      clusters.push_back(current);
      current.first = i;
    }
    current.last = i;
  }
  clusters.push_back(current);
  return clusters;
}

}  // namespace ekf_slam
