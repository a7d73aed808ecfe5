// Stage 2: split-and-merge / Douglas–Peucker (thesis §4.2.2.2) of one cluster
// into pieces that one straight line explains within hf.
#pragma once

#include <vector>

#include "ekf_slam_core/features/clustering.h"

namespace ekf_slam {

// Splits points[cluster] recursively at the point farthest from the chord
// between a piece's first and last point while that distance exceeds
// options.split_threshold (hf), then merges adjacent pieces again where one
// total-least-squares line fits their union with every point within hf and
// the two pieces' own lines agree within options.merge_chi2.
// Adjacent pieces share their split point (piece k's last index is piece
// k+1's first), so the pieces tile the cluster. A cluster of fewer than
// three points comes back as one piece.
std::vector<IndexSpan> splitAndMerge(const std::vector<ScanPoint>& points, const IndexSpan& cluster,
                                     const FeatureOptions& options);

}  // namespace ekf_slam
