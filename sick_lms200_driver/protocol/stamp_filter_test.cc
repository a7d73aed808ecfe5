#include "sick_lms200_driver/protocol/stamp_filter.h"

#include <gtest/gtest.h>

#include <random>

namespace sick_lms200 {
namespace {

constexpr double kPeriod = 1.0 / 75.0;

TEST(StampFilter, RemovesSporadicHostDelays) {
  StampFilter filter(kPeriod);
  std::mt19937 rng(5);
  std::exponential_distribution<double> delay(1.0 / 0.0003);  // mean 0.3 ms
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  double worst_raw = 0.0, worst_filtered = 0.0;
  for (int k = 0; k < 500; ++k) {
    const double truth = 1000.0 + k * 8 * kPeriod;
    double late = delay(rng);
    if (uniform(rng) < 0.1) late += 0.002 + 0.0025 * uniform(rng);  // thread preempted
    const double filtered = filter.filter(truth + late);
    worst_raw = std::max(worst_raw, late);
    if (k > 10) worst_filtered = std::max(worst_filtered, filtered - truth);
    EXPECT_GE(filtered - truth, -1e-9) << k;  // never earlier than the truth
  }
  EXPECT_GT(worst_raw, 0.004);
  EXPECT_LT(worst_filtered, 0.001);
}

TEST(StampFilter, FollowsASlowMirrorAndSkippedScans) {
  StampFilter filter(kPeriod);
  const double slow_period = kPeriod * 1.0005;  // 500 ppm slower than nominal
  double truth = 50.0;
  for (int k = 0; k < 300; ++k) {
    truth += (k % 7 == 3 ? 16 : 8) * slow_period;  // one scan in 7 lost to a CRC error
    const double filtered = filter.filter(truth);
    EXPECT_NEAR(filtered, truth, 2e-4) << k;
  }
}

TEST(StampFilter, RestartsWhenTimeJumps) {
  StampFilter filter(kPeriod);
  filter.filter(100.0);
  filter.filter(100.0 + 8 * kPeriod);
  EXPECT_DOUBLE_EQ(filter.filter(90.0), 90.0);  // time went backwards
  EXPECT_DOUBLE_EQ(filter.filter(95.0), 95.0);  // a gap of seconds
  // A lasting shift (three late estimates in a row) is followed, not filtered.
  const double shifted = 95.0 + 0.006;
  filter.filter(shifted + 8 * kPeriod);
  filter.filter(shifted + 16 * kPeriod);
  EXPECT_DOUBLE_EQ(filter.filter(shifted + 24 * kPeriod), shifted + 24 * kPeriod);
}

}  // namespace
}  // namespace sick_lms200
