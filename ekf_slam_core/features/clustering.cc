#include "ekf_slam_core/features/clustering.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ekf_slam {

ScanPoint makeScanPoint(int beam, double range, double bearing) {
  ScanPoint p;
  p.beam = beam;
  p.range = range;
  p.bearing = bearing;
  p.direction = Vector2(std::cos(bearing), std::sin(bearing));
  p.xy = range * p.direction;
  return p;
}

std::vector<ScanPoint> scanToPoints(const Scan& scan) {
  std::vector<ScanPoint> points;
  points.reserve(scan.ranges.size());
  // Beam directions by rotating the previous one through the increment,
  // re-seeded exactly every 32 beams (rounding stays ~1e-15): one sincos per
  // 32 beams instead of one per beam.
  const double cos_step = std::cos(scan.angle_increment);
  const double sin_step = std::sin(scan.angle_increment);
  Vector2 direction(1.0, 0.0);
  for (int i = 0; i < scan.size(); ++i) {
    if (i % 32 == 0) {
      direction = Vector2(std::cos(scan.angle(i)), std::sin(scan.angle(i)));
    } else {
      direction = Vector2(direction.x() * cos_step - direction.y() * sin_step,
                          direction.y() * cos_step + direction.x() * sin_step);
    }
    if (!scan.isValid(i)) continue;
    ScanPoint p;
    p.beam = i;
    p.range = scan.ranges[i];
    p.bearing = scan.angle(i);
    p.direction = direction;
    p.xy = p.range * direction;
    points.push_back(p);
  }
  return points;
}

namespace {

// A surface seen at incidence λ between two beams Δφ apart leaves a gap of
// r sinΔφ / sin(λ − Δφ) (law of sines in the triangle laser, a, b); a wider
// gap means a steeper surface than λ, i.e. a different object. Returns the
// factor of r, or −1 when Δφ >= λ (no surface can bridge the beams).
double adaptiveFactor(double delta, double lambda) {
  if (delta >= lambda) return -1.0;
  return std::sin(delta) / std::sin(lambda - delta);
}

}  // namespace

double clusterGapThreshold(const ScanPoint& a, const ScanPoint& b, const FeatureOptions& options) {
  if (options.cluster_mode == ClusterMode::kFixed) return options.cluster_threshold;
  const double factor =
      adaptiveFactor(std::abs(b.bearing - a.bearing), options.cluster_incidence_angle);
  if (factor < 0.0) return options.cluster_threshold;
  return std::max(options.cluster_threshold, a.range * factor + 3.0 * options.range_sigma);
}

std::vector<IndexSpan> clusterPoints(const std::vector<ScanPoint>& points,
                                     const FeatureOptions& options) {
  std::vector<IndexSpan> clusters;
  if (points.empty()) return clusters;
  // The threshold depends on the pair only through the first range and the
  // number of beams between them: precompute r sinΔφ / sin(λ − Δφ) per beam
  // step (no trig per pair); a negative factor marks Δφ >= λ.
  const int max_step = options.cluster_max_invalid_beams + 1;
  std::vector<double> factor(max_step + 1, -1.0);
  if (points.size() > 1) {
    const double increment = std::abs(points[1].bearing - points[0].bearing) /
                             std::max(1, std::abs(points[1].beam - points[0].beam));
    for (int step = 1; step <= max_step; ++step) {
      factor[step] = adaptiveFactor(step * increment, options.cluster_incidence_angle);
    }
  }
  IndexSpan current{0, 0};
  for (int i = 1; i < static_cast<int>(points.size()); ++i) {
    const ScanPoint& a = points[i - 1];
    const ScanPoint& b = points[i];
    const int step = std::abs(b.beam - a.beam);
    bool split = step > max_step;
    if (!split) {
      double threshold = options.cluster_threshold;
      if (options.cluster_mode == ClusterMode::kAdaptive && factor[step] >= 0.0) {
        threshold = std::max(threshold, a.range * factor[step] + 3.0 * options.range_sigma);
      }
      split = (b.xy - a.xy).squaredNorm() > threshold * threshold;
    }
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
