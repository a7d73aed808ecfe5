#include "ekf_slam_core/pipeline/odometry_track.h"

#include <gtest/gtest.h>

namespace ekf_slam {
namespace {

TEST(OdometryTrack, InterpolatesUnsortedSamplesAcrossThePiWrap) {
  OdometryTrack track;
  track.add(2.0, Pose2(2.0, 0.0, -kPi + 0.1));
  track.add(1.0, Pose2(1.0, 0.0, kPi - 0.1));  // out of time order
  track.add(std::nan(""), Pose2());
  track.finalize();
  EXPECT_EQ(track.size(), 2u);
  EXPECT_EQ(track.dropped(), 1);
  Pose2 p;
  double distance = 0.0;
  ASSERT_EQ(track.poseAt(1.5, 1.5, &p, &distance), OdometryTrack::Lookup::kInterpolated);
  EXPECT_NEAR(p.x, 1.5, 1e-12);
  EXPECT_NEAR(std::abs(p.theta), kPi, 1e-12) << "halfway across ±π, not through 0";
  EXPECT_NEAR(distance, 0.5, 1e-12);
  ASSERT_EQ(track.poseAt(1.25, 1.5, &p), OdometryTrack::Lookup::kInterpolated);
  EXPECT_NEAR(p.theta, kPi - 0.05, 1e-12);  // a quarter of the 0.2 rad step through π
  EXPECT_EQ(track.poseAt(1.25, 0.5, &p), OdometryTrack::Lookup::kNearest) << "gap 1 s > 0.5 s";
}

TEST(OdometryTrack, GapsAndEndsFallBackToTheNearestSample) {
  OdometryTrack track;
  track.add(0.0, Pose2(0, 0, 0));
  track.add(3.0, Pose2(3, 0, 0));
  track.finalize();
  Pose2 p;
  EXPECT_EQ(track.poseAt(1.0, 0.5, &p), OdometryTrack::Lookup::kNearest);
  EXPECT_EQ(p.x, 0.0);
  EXPECT_EQ(track.poseAt(2.5, 0.5, &p), OdometryTrack::Lookup::kNearest);
  EXPECT_EQ(p.x, 3.0);
  EXPECT_EQ(track.poseAt(-1.0, 0.5, &p), OdometryTrack::Lookup::kNearest);
  EXPECT_EQ(track.poseAt(3.0, 0.5, &p), OdometryTrack::Lookup::kInterpolated);
  EXPECT_EQ(OdometryTrack().poseAt(1.0, 0.5, &p), OdometryTrack::Lookup::kNone);
}

}  // namespace
}  // namespace ekf_slam
