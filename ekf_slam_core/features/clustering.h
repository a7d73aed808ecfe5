// Stage 1 of the extractor: valid readings → Cartesian points → clusters
// (thesis §4.2.2.1). Frame: laser frame, metres and radians.
#pragma once

#include <vector>

#include "ekf_slam_core/features/feature_options.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

// One valid reading, in scan order.
struct ScanPoint {
  int beam = 0;          // index into Scan::ranges
  double range = 0.0;    // m
  double bearing = 0.0;  // rad, laser frame
  Vector2 direction;     // (cos bearing, sin bearing), computed once per beam
  Vector2 xy;            // m, laser frame: range · direction
};

ScanPoint makeScanPoint(int beam, double range, double bearing);

// Inclusive index range [first, last] into a ScanPoint vector.
struct IndexSpan {
  int first = 0;
  int last = -1;
  int size() const { return last - first + 1; }
};

// The valid readings of `scan` (Scan::isValid), in beam order.
std::vector<ScanPoint> scanToPoints(const Scan& scan);

// Largest gap (m) allowed between the neighbours `a` and `b` (in that order)
// before a new cluster starts, following options.cluster_mode.
double clusterGapThreshold(const ScanPoint& a, const ScanPoint& b, const FeatureOptions& options);

// Consecutive points grouped into clusters: a new cluster starts where the
// Euclidean gap exceeds clusterGapThreshold, or where more than
// options.cluster_max_invalid_beams invalid beams lie between neighbours.
// Every point belongs to exactly one cluster (single-point clusters included).
std::vector<IndexSpan> clusterPoints(const std::vector<ScanPoint>& points,
                                     const FeatureOptions& options);

}  // namespace ekf_slam
