// Reproduces the conclusions of thesis §3.3.1 about the Kalman gain.
#include "ekf_slam_core/filter/scalar_kalman.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ekf_slam {
namespace {

TEST(ScalarKalman, GainIsBetweenZeroAndOneAndFollowsTheVarianceRatio) {
  for (double ratio : {1e-6, 0.01, 1.0, 100.0, 1e6}) {
    ScalarKalman filter(0.0, 1.0);
    const double gain = filter.update(1.0, ratio);  // R / P⁻ = ratio
    EXPECT_GT(gain, 0.0);
    EXPECT_LT(gain, 1.0);
    EXPECT_NEAR(gain, 1.0 / (1.0 + ratio), 1e-15);
  }
}

TEST(ScalarKalman, AccurateObservationIsTrustedInaccurateOneBarelyMoves) {
  ScalarKalman trusting(0.0, 4.0);
  trusting.predict(1.0, 0.0);
  trusting.update(3.0, 1e-8);  // R ≪ P⁻: estimate ≈ z
  EXPECT_NEAR(trusting.mean(), 3.0, 1e-6);

  ScalarKalman sceptical(0.0, 1e-4);
  sceptical.predict(1.0, 0.0);
  sceptical.update(3.0, 1e4);  // R ≫ P⁻: estimate ≈ prior
  EXPECT_NEAR(sceptical.mean(), 1.0, 1e-6);
}

TEST(ScalarKalman, VarianceDoesNotDependOnTheObservedValue) {
  ScalarKalman a(0.0, 2.0), b(0.0, 2.0);
  a.update(-100.0, 0.5);
  b.update(42.0, 0.5);
  EXPECT_DOUBLE_EQ(a.variance(), b.variance());
  EXPECT_NE(a.mean(), b.mean());
}

TEST(ScalarKalman, ObservationsStopTheGrowthOfTheVariance) {
  ScalarKalman dead_reckoning(0.0, 0.0), observed(0.0, 0.0);
  for (int k = 0; k < 200; ++k) {
    dead_reckoning.predict(0.1, 0.01);
    observed.predict(0.1, 0.01);
    observed.update(0.1 * (k + 1), 0.04);
  }
  EXPECT_NEAR(dead_reckoning.variance(), 2.0, 1e-9);  // grows without bound: 200 · 0.01
  // Converges to the steady state of P = (P + Q) R / (P + Q + R).
  const double q = 0.01, r = 0.04;
  const double steady = (-q + std::sqrt(q * q + 4 * q * r)) / 2.0;
  EXPECT_NEAR(observed.variance(), steady, 1e-9);
  EXPECT_LT(observed.variance(), r);
}

}  // namespace
}  // namespace ekf_slam
