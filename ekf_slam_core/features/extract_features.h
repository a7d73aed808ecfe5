// Laser feature extraction (thesis §4.2.2, §4.3.2), the one entry point:
//
//   Scan → valid points → clusters (§4.2.2.1) → split-and-merge (§4.2.2.2)
//        → total-least-squares lines with covariance → corners and segment ends
//
// Every output is in the laser (sensor) frame of the scan: x forward, y left,
// metres and radians. The filter consumes each PointFeature as a range–bearing
// observation (range, bearing) with covariance `range_bearing_covariance`,
// and each LineFeature as (p, θ) with `covariance`.
// The stages are in clustering.h, split_and_merge.h and line_fit.h.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/features/clustering.h"
#include "ekf_slam_core/features/feature_options.h"
#include "ekf_slam_core/features/line_fit.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

// A wall segment: the line x cos θ + y sin θ = p through a run of beams.
struct LineFeature {
  double p = 0.0;                        // m, >= 0, distance of the line from the laser origin
  double theta = 0.0;                    // rad, [-π, π), direction of the line's normal
  Matrix2 covariance = Matrix2::Zero();  // of (p, θ): [m², m·rad; m·rad, rad²]
  Vector2 start = Vector2::Zero();       // m, first fitted point projected onto the line
  Vector2 end = Vector2::Zero();         // m, last fitted point projected (scan order)
  int first_beam = 0;                    // Scan::ranges index of the first fitted point
  int last_beam = 0;                     // ... and of the last
  int num_points = 0;                    // points in the fit
  double rms_residual = 0.0;             // m, orthogonal fit residual
  int cluster = 0;                       // index into FeatureSet::clusters

  double length() const { return (end - start).norm(); }
  // How far first-order (p, θ) covariance is from the truth for this line:
  // p(θ) = n(θ)·c is curved (∂²p/∂θ² = −p), so a θ error of σ_θ moves p by
  // ½ p σ_θ² beyond the linear term. Returned in units of p's standard
  // deviation given θ. Below ~0.3 the Gaussian in (p, θ) is faithful; short
  // lines far away (p ≫ length) exceed it and their (p, θ) error is
  // banana-shaped: gate or down-weight them in the filter.
  double linearizationError() const;
};

enum class PointKind {
  kCorner,      // intersection of two adjacent lines meeting at >= corner_min_angle
  kSegmentEnd,  // outer end of a cluster's first or last line
};

// Why a point is, or is not, offered as a landmark.
enum class EndpointContext {
  kCorner,        // a corner: landmark candidate
  kFrontEdge,     // the object ends in front of a farther background: candidate
  kOccluded,      // the next beam hits something nearer: an occlusion edge, moves
                  // with the viewpoint, never a landmark
  kNoReturn,      // the next beam is invalid (beyond range, NaN): cannot tell, not a landmark
  kScanBoundary,  // the line runs out of the field of view: not a landmark
  kUnresolved,    // the end is not pinned down: the gap to the next beam exceeds
                  // endpoint_max_gap, the last readings left the line (trimmed),
                  // or the next reading lies on the line's extension (the wall
                  // goes on beyond a sparse stretch at grazing incidence)
};

struct PointFeature {
  PointKind kind = PointKind::kCorner;
  EndpointContext context = EndpointContext::kCorner;
  bool landmark_candidate = false;                     // true only for kCorner and kFrontEdge
  Vector2 position = Vector2::Zero();                  // m, laser frame
  Matrix2 covariance = Matrix2::Zero();                // of position: m²
  double range = 0.0;                                  // m, |position|
  double bearing = 0.0;                                // rad, atan2(y, x), laser frame
  Matrix2 range_bearing_covariance = Matrix2::Zero();  // of (range, bearing): [m², m·rad; ., rad²]
  int line = -1;        // index into FeatureSet::lines (a corner: the line before it in scan order)
  int other_line = -1;  // a corner: the line after it; -1 for segment ends
  double corner_angle = 0.0;  // rad, kCorner: angle between the lines folded into [0, π/2]
};

struct FeatureSet {
  std::vector<ScanPoint> points;    // valid readings, scan order
  std::vector<IndexSpan> clusters;  // into `points`
  std::vector<IndexSpan> pieces;    // split-and-merge pieces into `points`, all clusters
  std::vector<LineFeature> lines;   // accepted lines, scan order
  std::vector<PointFeature> points_of_interest;  // corners and segment ends, scan order
  std::string error;  // non-empty when the scan or the options were rejected (then no features)

  int countCorners() const;
  int countLandmarkCandidates() const;
};

// Checks features that did not come straight from extractFeatures (a
// message from another node, a file): every landmark candidate must have a
// positive finite range, a finite bearing and a symmetric positive-definite
// range–bearing covariance, because the filter inverts it. Empty when usable,
// else names the first bad point and why.
std::string validateFeatureSet(const FeatureSet& features);

// Runs every stage. Never throws; bad options or scan geometry give an empty
// set with `error` naming the bad field; invalid readings are skipped.
FeatureSet extractFeatures(const Scan& scan, const FeatureOptions& options);

}  // namespace ekf_slam
