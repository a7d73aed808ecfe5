// Every threshold of the laser feature extractor (thesis §4.2.2, §4.3.2),
// with its unit, default and admissible values (visitFields, see
// geometry/option_fields.h). validateFeatureOptions() rejects bad values with
// a message naming the field; the configuration loaders read the same
// declarations.
#pragma once

#include <string>

#include "ekf_slam_core/geometry/angle.h"
#include "ekf_slam_core/geometry/option_fields.h"

namespace ekf_slam {

enum class ClusterMode {
  kFixed,     // thesis §4.2.2.1: break where the gap between neighbours exceeds hc
  kAdaptive,  // break where the gap exceeds max(hc, range-adaptive bound), see below
};

struct FeatureOptions {
  // --- sensor noise (per beam, independent), used for every covariance ---
  double range_sigma = 0.01;     // m, 1σ range noise of one reading (LMS200: ~1 cm)
  double bearing_sigma = 0.001;  // rad, 1σ bearing jitter of one beam (~0.06°)

  // --- clustering (§4.2.2.1) ---
  ClusterMode cluster_mode = ClusterMode::kAdaptive;
  // hc (m): the thesis's fixed gap threshold; in kAdaptive mode the floor of
  // the adaptive threshold.
  double cluster_threshold = 0.10;
  // λ (rad), kAdaptive only: the shallowest incidence angle at which a surface
  // still counts as continuous. Two neighbours at bearings Δφ apart are split
  // when their gap exceeds r·sin Δφ / sin(λ − Δφ) + 3·range_sigma
  // (Borges & Aldon's adaptive breakpoint detector), r = range of the first.
  double cluster_incidence_angle = degToRad(10.0);
  // Invalid readings (NaN, no return) inside a wall do not break a cluster
  // unless more than this many of them are consecutive (beams).
  int cluster_max_invalid_beams = 2;

  // --- split-and-merge (§4.2.2.2) ---
  // hf (m): a cluster is split at its farthest point from the chord while that
  // distance exceeds hf; adjacent pieces are merged again when one
  // total-least-squares line fits both within hf and their lines agree
  // (merge_chi2).
  double split_threshold = 0.05;
  // Adjacent pieces are merged only when their fitted lines agree: squared
  // Mahalanobis distance of (Δp, Δθ) under the summed covariances below this
  // (χ², 2 dof; 9.21 = 99 %).
  double merge_chi2 = 9.21;
  int min_line_points = 5;       // fitted points a line needs (after the guard below)
  double min_line_length = 0.2;  // m, distance between the projected end points
  // Beams on each side of a split point left out of both neighbouring fits
  // (the split point itself is always left out), so that a point straddling
  // a corner does not bend either line. 0 keeps only the split point out.
  int break_guard_points = 1;
  // Up to this many readings at each end of a fitted line are dropped while
  // the line through the other readings predicts them worse than 3σ: the
  // first readings of a short adjacent face or a mixed pixel that the split
  // (within hf) could not separate. A trimmed outer end is no landmark.
  int end_trim_points = 2;

  // --- corners and segment ends ---
  // Two adjacent lines of one cluster form a corner when the angle between
  // them (folded into [0, 90°]) is at least this (rad).
  double corner_min_angle = degToRad(30.0);
  // ... and their intersection lies within this distance (m) of the split
  // point between them.
  double corner_max_distance = 0.2;
  // A segment end in front of a farther background is a landmark candidate
  // only when the true end is pinned down to this along-line uncertainty (m):
  // the gap between the last hit and where the next beam crosses the line.
  double endpoint_max_gap = 0.3;
  // 1σ (m), isotropic, of where the extraction puts a corner or a segment end
  // beyond what the beam noise explains: the same physical point seen from
  // different places lands up to a few centimetres apart (a door jamb's
  // chamfered or rasterised corner, lines that bend near their ends), and
  // those errors do not average out over scans from one viewpoint. Added to
  // every point's covariance. Without it a corner seen at arm's length claims
  // millimetres and a few such sightings make the filter's heading
  // overconfident (docs/results.md, "The pose NEES"). 0: beam noise only (thesis).
  double point_model_sigma = 0.0;

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.choice("cluster_mode", cluster_mode,
             {{ClusterMode::kFixed, "fixed"}, {ClusterMode::kAdaptive, "adaptive"}});
    v.number("range_sigma", range_sigma, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("bearing_sigma", bearing_sigma, Bounds::closed(0.0, 1.0, "rad"));
    v.number("cluster_threshold", cluster_threshold, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("cluster_incidence_angle", cluster_incidence_angle,
             Bounds::open(0.0, kPi / 2.0, "rad"));
    v.integer("cluster_max_invalid_beams", cluster_max_invalid_beams,
              Bounds::closed(0, 1000, "beams"));
    v.number("split_threshold", split_threshold, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("merge_chi2", merge_chi2, Bounds::openClosed(0.0, 1e6));
    v.integer("min_line_points", min_line_points, Bounds::closed(2, 100000));
    v.number("min_line_length", min_line_length, Bounds::closed(0.0, 100.0, "m"));
    v.integer("break_guard_points", break_guard_points, Bounds::closed(0, 100));
    v.integer("end_trim_points", end_trim_points, Bounds::closed(0, 100));
    v.number("corner_min_angle", corner_min_angle, Bounds::openClosed(0.0, kPi / 2.0, "rad"));
    v.number("corner_max_distance", corner_max_distance, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("endpoint_max_gap", endpoint_max_gap, Bounds::closed(0.0, 10.0, "m"));
    v.number("point_model_sigma", point_model_sigma, Bounds::closed(0.0, 1.0, "m"));
  }
};

// Empty when every field is usable; otherwise a message naming the first bad
// field, e.g. "FeatureOptions.split_threshold must be > 0 (m), got -1".
std::string validateFeatureOptions(const FeatureOptions& options);

}  // namespace ekf_slam
