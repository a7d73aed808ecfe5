// Chi-square quantiles for validation gates and consistency bands.
#pragma once

namespace ekf_slam {

// The value x with P(χ²_dof ≤ x) = probability. probability in (0, 1), dof > 0.
double chiSquareQuantile(double probability, double dof);

// Two-sided band for the average of `samples` independent χ²_dof values at
// confidence `confidence` (e.g. 0.95): [lower, upper].
struct ChiSquareBand {
  double lower;
  double upper;
};
ChiSquareBand averageChiSquareBand(double dof, int samples, double confidence = 0.95);

}  // namespace ekf_slam
