// Total-least-squares line fit with first-order covariance propagated from
// every beam's range and bearing noise (not from the two end points, which
// under-estimates, thesis §4.3.3), line intersection and the Cartesian →
// range–bearing conversion, each with the Jacobians that carry covariances.
// Derivation in the code's symbols: docs/features.md.
//
// Line normal form (laser frame): x cos θ + y sin θ = p, with p >= 0 (m) the
// distance from the laser origin and θ in [-π, π) (rad) the direction of the
// normal from the origin towards the line.
#pragma once

#include <vector>

#include "ekf_slam_core/features/clustering.h"

namespace ekf_slam {

struct LineFit {
  double p = 0.0;                        // m, >= 0
  double theta = 0.0;                    // rad, [-π, π)
  Matrix2 covariance = Matrix2::Zero();  // of (p, θ): [m², m·rad; m·rad, rad²]
  Vector2 centroid = Vector2::Zero();    // m, laser frame
  double rms_residual = 0.0;             // m, orthogonal residuals of the fitted points
  double max_residual = 0.0;             // m
  int num_points = 0;

  Vector2 normal() const;     // (cos θ, sin θ)
  Vector2 direction() const;  // (−sin θ, cos θ): the normal turned +90°
  // Orthogonal projection of `point` onto the line.
  Vector2 project(const Vector2& point) const;
};

// Fits the line through points[first..last] (inclusive) minimising the sum of
// squared orthogonal distances. covariance = Σ_i J_i diag(σ_r², σ_φ²) J_iᵀ with
// J_i = ∂(p, θ)/∂(r_i, φ_i). When `J_per_point` is given it receives the J_i
// (one per fitted point, in order). Returns false (outputs untouched) for
// fewer than two points or points without a unique best line (all coincident
// or isotropic spread).
bool fitLine(const std::vector<ScanPoint>& points, int first, int last, double range_sigma,
             double bearing_sigma, LineFit* fit, std::vector<Matrix2>* J_per_point = nullptr);

// The same fit without the covariance (left zero): p, θ, centroid and
// residuals only, for split-and-merge decisions.
bool fitLineGeometry(const std::vector<ScanPoint>& points, int first, int last, LineFit* fit);

// Intersection of the lines (p1, θ1) and (p2, θ2). J_out_line1/2 =
// ∂point/∂(p_k, θ_k). Returns false when the lines are (near) parallel,
// |sin(θ2 − θ1)| < 1e-6.
bool intersectLines(double p1, double theta1, double p2, double theta2, Vector2* point,
                    Matrix2* J_out_line1 = nullptr, Matrix2* J_out_line2 = nullptr);

// (r, φ) of a laser-frame point with J_out_point = ∂(r, φ)/∂(x, y). Returns
// false at the origin.
bool pointToRangeBearing(const Vector2& point, Vector2* range_bearing,
                         Matrix2* J_out_point = nullptr);

}  // namespace ekf_slam
