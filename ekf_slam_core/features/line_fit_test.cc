// Proves the line fit, the intersection and the polar conversion: analytic
// Jacobians against central differences, and the propagated (p, θ)
// covariance against Monte Carlo draws (normalised error squared inside the
// chi-square band).
#include "ekf_slam_core/features/line_fit.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using testing::numericalJacobian;

std::vector<ScanPoint> pointsFromPolar(const VectorXd& polar) {
  std::vector<ScanPoint> points(polar.size() / 2);
  for (size_t i = 0; i < points.size(); ++i) {
    points[i] = makeScanPoint(static_cast<int>(i), polar(2 * i), polar(2 * i + 1));
  }
  return points;
}

// Ranges and bearings of `count` beams from `bearing0` in steps of `step`
// hitting the line (p, θ), with small deterministic wiggles so the fit has
// residuals.
VectorXd beamsOnLine(double p, double theta, double bearing0, double step, int count,
                     double wiggle) {
  VectorXd polar(2 * count);
  for (int i = 0; i < count; ++i) {
    const double bearing = bearing0 + i * step;
    polar(2 * i) = p / std::cos(bearing - theta) + wiggle * std::sin(1.7 * i + 0.3);
    polar(2 * i + 1) = bearing;
  }
  return polar;
}

struct LineCase {
  double p, theta, bearing0, step;
  int count;
};

class LineFitJacobian : public ::testing::TestWithParam<LineCase> {};

// Normals in every quadrant, including θ near ±π and a line whose raw fit has
// p < 0 (the flip to p >= 0 must carry the Jacobian sign).
INSTANTIATE_TEST_SUITE_P(Lines, LineFitJacobian,
                         ::testing::Values(LineCase{2.0, 0.1, -0.5, 0.02, 30},
                                           LineCase{1.5, kPi - 0.02, 2.7, 0.03, 20},
                                           LineCase{3.0, -kPi + 0.01, -2.9, 0.01, 40},
                                           LineCase{0.7, -1.2, -2.0, 0.05, 12},
                                           LineCase{4.0, 2.0, 1.5, 0.04, 5}));

TEST_P(LineFitJacobian, MatchesCentralDifferences) {
  const LineCase c = GetParam();
  const VectorXd polar = beamsOnLine(c.p, c.theta, c.bearing0, c.step, c.count, 0.01);
  const std::vector<ScanPoint> points = pointsFromPolar(polar);
  LineFit fit;
  std::vector<Matrix2> J;
  ASSERT_TRUE(fitLine(points, 0, c.count - 1, 0.01, 0.001, &fit, &J));
  EXPECT_NEAR(fit.p, c.p, 0.02);
  EXPECT_NEAR(wrapAngle(fit.theta - c.theta), 0.0, 0.02);
  EXPECT_GE(fit.p, 0.0);
  ASSERT_EQ(static_cast<int>(J.size()), c.count);
  const auto f = [](const VectorXd& v) -> VectorXd {
    LineFit out;
    const std::vector<ScanPoint> pts = pointsFromPolar(v);
    EXPECT_TRUE(fitLine(pts, 0, static_cast<int>(pts.size()) - 1, 0.01, 0.001, &out));
    return Vector2(out.p, out.theta);
  };
  const MatrixXd numerical = numericalJacobian(f, polar, {1});
  for (int i = 0; i < c.count; ++i) {
    const Matrix2 expected = numerical.block<2, 2>(0, 2 * i);
    EXPECT_LT((J[i] - expected).cwiseAbs().maxCoeff(), 1e-6 * (1.0 + expected.norm()))
        << "point " << i << "\nanalytic\n"
        << J[i] << "\nnumerical\n"
        << expected;
  }
  // The covariance is Σ J_i diag(σ_r², σ_φ²) J_iᵀ.
  Matrix2 covariance = Matrix2::Zero();
  const Matrix2 R = Vector2(1e-4, 1e-6).asDiagonal();
  for (const Matrix2& Ji : J) covariance += Ji * R * Ji.transpose();
  EXPECT_TRUE(fit.covariance.isApprox(covariance, 1e-12));
}

TEST(LineFit, NegativeRawDistanceFlipsToPositiveP) {
  // The line y = -1 seen below the sensor: the fit must report p = 1, θ = -π/2.
  VectorXd polar = beamsOnLine(1.0, -kPi / 2.0, -2.0, 0.05, 20, 0.0);
  LineFit fit;
  // Noise-free readings and no noise model: nothing to correct, exact answer.
  ASSERT_TRUE(fitLine(pointsFromPolar(polar), 0, 19, 0.0, 0.0, &fit));
  EXPECT_NEAR(fit.p, 1.0, 1e-9);
  EXPECT_NEAR(fit.theta, -kPi / 2.0, 1e-9);
  EXPECT_NEAR(fit.max_residual, 0.0, 1e-9);
}

TEST(LineFit, RejectsTooFewOrCoincidentPoints) {
  LineFit fit;
  const std::vector<ScanPoint> one = pointsFromPolar(Vector2(1.0, 0.0));
  EXPECT_FALSE(fitLine(one, 0, 0, 0.01, 0.0, &fit));
  VectorXd same(6);
  same << 1.0, 0.2, 1.0, 0.2, 1.0, 0.2;
  EXPECT_FALSE(fitLine(pointsFromPolar(same), 0, 2, 0.01, 0.0, &fit));
  EXPECT_FALSE(fitLine(one, 0, 5, 0.01, 0.0, &fit));  // span past the end
}

TEST(LineIntersection, JacobiansMatchCentralDifferences) {
  for (const Eigen::Vector4d lines :
       {Eigen::Vector4d(2.0, 0.1, 1.5, 1.7), Eigen::Vector4d(3.0, kPi - 0.01, 2.0, -2.0),
        Eigen::Vector4d(0.5, -1.0, 4.0, 0.9)}) {
    Vector2 point;
    Matrix2 J1, J2;
    ASSERT_TRUE(intersectLines(lines(0), lines(1), lines(2), lines(3), &point, &J1, &J2));
    // The point lies on both lines.
    EXPECT_NEAR(point.dot(Vector2(std::cos(lines(1)), std::sin(lines(1)))), lines(0), 1e-12);
    EXPECT_NEAR(point.dot(Vector2(std::cos(lines(3)), std::sin(lines(3)))), lines(2), 1e-12);
    const auto f = [](const VectorXd& v) -> VectorXd {
      Vector2 x;
      EXPECT_TRUE(intersectLines(v(0), v(1), v(2), v(3), &x));
      return x;
    };
    const MatrixXd numerical = numericalJacobian(f, lines);
    EXPECT_TRUE(J1.isApprox(numerical.leftCols<2>(), 1e-6)) << J1 << "\n" << numerical;
    EXPECT_TRUE(J2.isApprox(numerical.rightCols<2>(), 1e-6)) << J2 << "\n" << numerical;
  }
  Vector2 point;
  EXPECT_FALSE(intersectLines(1.0, 0.3, 2.0, 0.3, &point));        // parallel
  EXPECT_FALSE(intersectLines(1.0, 0.3, 2.0, 0.3 + kPi, &point));  // antiparallel
}

TEST(RangeBearing, JacobianMatchesCentralDifferencesNearPi) {
  for (const Vector2 xy :
       {Vector2(1.0, 2.0), Vector2(-3.0, 1e-3), Vector2(-3.0, -1e-3), Vector2(0.05, -0.02)}) {
    Vector2 rb;
    Matrix2 J;
    ASSERT_TRUE(pointToRangeBearing(xy, &rb, &J));
    EXPECT_NEAR(rb(0), xy.norm(), 1e-12);
    const auto f = [](const VectorXd& v) -> VectorXd {
      Vector2 out;
      EXPECT_TRUE(pointToRangeBearing(v, &out));
      return out;
    };
    EXPECT_TRUE(J.isApprox(numericalJacobian(f, xy, {1}), 1e-6)) << xy.transpose();
  }
  Vector2 rb;
  EXPECT_FALSE(pointToRangeBearing(Vector2::Zero(), &rb));
}

// Monte Carlo: beams with range noise σ_r and bearing jitter σ_φ hit a wall;
// the normalised error squared of the fitted (p, θ) against the true line
// averages to 2 within the chi-square band.
TEST(LineFit, CovarianceIsConsistentOverNoisyDraws) {
  const double sigma_r = 0.01, sigma_phi = 0.001;
  const double p_true = 2.5, theta_true = 0.4;
  std::mt19937 rng(7);
  std::normal_distribution<double> range_noise(0.0, sigma_r), bearing_noise(0.0, sigma_phi);
  const int draws = 1000, beams = 60;
  double nees_sum = 0.0;
  for (int k = 0; k < draws; ++k) {
    std::vector<ScanPoint> points(beams);
    for (int i = 0; i < beams; ++i) {
      const double reported = -0.6 + 0.02 * i;
      const double actual = reported + bearing_noise(rng);  // where the beam really went
      points[i] =
          makeScanPoint(i, p_true / std::cos(actual - theta_true) + range_noise(rng), reported);
    }
    LineFit fit;
    ASSERT_TRUE(fitLine(points, 0, beams - 1, sigma_r, sigma_phi, &fit));
    const Vector2 error(fit.p - p_true, wrapAngle(fit.theta - theta_true));
    nees_sum += error.dot(fit.covariance.inverse() * error);
  }
  const ChiSquareBand band = averageChiSquareBand(2.0, draws, 0.99);
  const double mean_nees = nees_sum / draws;
  EXPECT_GT(mean_nees, band.lower);
  EXPECT_LT(mean_nees, band.upper);
  std::printf("line fit mean NEES %.3f over %d draws (99%% band %.3f..%.3f)\n", mean_nees, draws,
              band.lower, band.upper);
}

// A short face seen obliquely: range noise runs along the beam, not across
// the line, so plain total least squares (the geometry-only fit) converges to
// a tilted line. The adjusted fit removes the expected noise scatter first;
// its mean error must be a small fraction of its σ while plain TLS is off by
// a measurable part of σ (which made 0.35 m carton faces inconsistent).
TEST(LineFit, AdjustedFitRemovesTheObliqueIncidenceBias) {
  const double sigma_r = 0.01, sigma_phi = 0.001;
  const double p_true = 1.0, theta_true = 0.2;
  std::mt19937 rng(11);
  std::normal_distribution<double> range_noise(0.0, sigma_r), bearing_noise(0.0, sigma_phi);
  const int draws = 4000, beams = 16;
  Vector2 adjusted_sum = Vector2::Zero(), plain_sum = Vector2::Zero();
  Matrix2 covariance_sum = Matrix2::Zero();
  for (int k = 0; k < draws; ++k) {
    std::vector<ScanPoint> points(beams);
    for (int i = 0; i < beams; ++i) {
      const double reported = 1.0 + 0.0087 * i;  // ~60° incidence, 0.5° steps
      const double actual = reported + bearing_noise(rng);
      points[i] =
          makeScanPoint(i, p_true / std::cos(actual - theta_true) + range_noise(rng), reported);
    }
    LineFit adjusted, plain;
    ASSERT_TRUE(fitLine(points, 0, beams - 1, sigma_r, sigma_phi, &adjusted));
    ASSERT_TRUE(fitLineGeometry(points, 0, beams - 1, &plain));
    adjusted_sum += Vector2(adjusted.p - p_true, wrapAngle(adjusted.theta - theta_true));
    plain_sum += Vector2(plain.p - p_true, wrapAngle(plain.theta - theta_true));
    covariance_sum += adjusted.covariance;
  }
  const Vector2 sd = (covariance_sum / draws).diagonal().cwiseSqrt();
  const Vector2 adjusted_bias = (adjusted_sum / draws).cwiseQuotient(sd);
  const Vector2 plain_bias = (plain_sum / draws).cwiseQuotient(sd);
  std::printf("bias in sigma units: adjusted (%.3f, %.3f), plain TLS (%.3f, %.3f)\n",
              adjusted_bias(0), adjusted_bias(1), plain_bias(0), plain_bias(1));
  // The Monte Carlo mean itself scatters by 1/sqrt(4000) = 0.016σ.
  EXPECT_LT(adjusted_bias.cwiseAbs().maxCoeff(), 0.06);
  EXPECT_GT(std::abs(plain_bias(1)), 0.2);
}

}  // namespace
}  // namespace ekf_slam
