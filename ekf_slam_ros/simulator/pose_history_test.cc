#include "ekf_slam_ros/simulator/pose_history.h"

#include <gtest/gtest.h>

namespace ekf_slam {
namespace sim {
namespace {

TEST(PoseHistoryTest, EmptyIsIdentity) {
  PoseHistory history;
  EXPECT_TRUE(history.empty());
  EXPECT_EQ(maxAbsDifference(history.at(3.0), Pose2()), 0.0);
}

TEST(PoseHistoryTest, InterpolatesBetweenEntriesAndClampsOutside) {
  PoseHistory history;
  history.add(1.0, Pose2(0.0, 0.0, 0.0));
  history.add(2.0, Pose2(1.0, 2.0, 0.4));
  EXPECT_LT(maxAbsDifference(history.at(1.25), Pose2(0.25, 0.5, 0.1)), 1e-12);
  EXPECT_LT(maxAbsDifference(history.at(0.0), Pose2(0.0, 0.0, 0.0)), 1e-12);
  EXPECT_LT(maxAbsDifference(history.at(5.0), Pose2(1.0, 2.0, 0.4)), 1e-12);
}

TEST(PoseHistoryTest, HeadingTakesTheShortArcAcrossPi) {
  PoseHistory history;
  history.add(0.0, Pose2(0.0, 0.0, 3.0));
  history.add(1.0, Pose2(0.0, 0.0, -3.0));  // 0.283 rad further, through pi
  const double halfway = history.at(0.5).theta;
  EXPECT_NEAR(std::abs(halfway), kPi, 1e-9);
}

TEST(PoseHistoryTest, OldEntriesAreDroppedButTheNewestKept) {
  PoseHistory history(0.5);
  for (int i = 0; i <= 100; ++i) history.add(i * 0.01, Pose2(i * 0.01, 0.0, 0.0));
  // 0.2 s is older than the span: clamped to the oldest kept entry (≥ 0.49 s).
  EXPECT_GE(history.at(0.2).x, 0.49 - 1e-12);
  EXPECT_NEAR(history.at(0.755).x, 0.755, 1e-12);
  // Going back in time is ignored.
  history.add(0.3, Pose2(-5.0, 0.0, 0.0));
  EXPECT_NEAR(history.at(2.0).x, 1.0, 1e-12);
}

}  // namespace
}  // namespace sim
}  // namespace ekf_slam
