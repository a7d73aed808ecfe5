// Self-test of the relation metric.
#include "ekf_slam_core/eval/relations.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <random>

namespace ekf_slam {
namespace {

std::vector<StampedPose> wiggle(int n) {
  std::vector<StampedPose> out;
  for (int i = 0; i < n; ++i) {
    out.push_back({1000.0 + 0.25 * i, Pose2(0.3 * i, std::sin(0.2 * i), 0.4 * i)});
  }
  return out;
}

std::vector<Relation> relationsOf(const std::vector<StampedPose>& truth) {
  std::vector<Relation> out;
  for (size_t i = 0; i + 3 < truth.size(); ++i) {
    out.push_back({truth[i].stamp, truth[i + 3].stamp, between(truth[i].pose, truth[i + 3].pose)});
  }
  return out;
}

TEST(Relations, GroundTruthScoresZeroAndAGlobalTransformDoesNotMatter) {
  const std::vector<StampedPose> truth = wiggle(50);
  const std::vector<Relation> relations = relationsOf(truth);
  RelationErrors e = evaluateRelations(relations, truth);
  EXPECT_EQ(e.used, e.relations);
  EXPECT_LT(e.translation.mean, 1e-12);
  EXPECT_LT(e.rotation.mean, 1e-12);
  // Relations are relative: moving the whole trajectory changes nothing.
  std::vector<StampedPose> moved = truth;
  for (StampedPose& p : moved) p.pose = compose(Pose2(5, -3, 2.0), p.pose);
  e = evaluateRelations(relations, moved);
  EXPECT_LT(e.translation.mean, 1e-9);
  EXPECT_LT(e.rotation.mean, 1e-9);
}

TEST(Relations, KnownPerturbationGivesKnownErrors) {
  std::vector<StampedPose> truth = wiggle(2);
  const std::vector<Relation> relations = {
      {truth[0].stamp, truth[1].stamp, between(truth[0].pose, truth[1].pose)}};
  // The second pose off by (0.3, 0.4) m in the frame of the first pose's
  // relation end, and rotated by 0.1 rad.
  std::vector<StampedPose> estimate = truth;
  estimate[1].pose = compose(truth[1].pose, Pose2(0.3, 0.4, 0.1));
  const RelationErrors e = evaluateRelations(relations, estimate);
  ASSERT_EQ(e.used, 1);
  EXPECT_NEAR(e.translation.mean, 0.5, 1e-12);
  EXPECT_NEAR(e.rotation.mean, 0.1, 1e-12);
  EXPECT_NEAR(e.translation_squared.mean, 0.25, 1e-12);
  ASSERT_EQ(e.spans.size(), 1u);
  EXPECT_NEAR(e.spans[0], 0.25, 1e-12);
}

TEST(Relations, ErrorsSplitBySpan) {
  // Relations 3 poses (0.75 s) and 20 poses (5 s) apart; only the far end
  // of the long ones is disturbed.
  const std::vector<StampedPose> truth = wiggle(40);
  std::vector<Relation> relations;
  for (int i = 0; i < 10; ++i) {
    relations.push_back(
        {truth[i].stamp, truth[i + 3].stamp, between(truth[i].pose, truth[i + 3].pose)});
    relations.push_back(
        {truth[i].stamp, truth[i + 20].stamp, between(truth[i].pose, truth[i + 20].pose)});
  }
  std::vector<StampedPose> estimate = truth;
  for (int i = 20; i < 30; ++i) estimate[i].pose = compose(truth[i].pose, Pose2(0.0, 0.2, 0.05));
  const std::vector<SpanBin> bins =
      errorsBySpan(evaluateRelations(relations, estimate), {0.0, 1.0, 10.0});
  ASSERT_EQ(bins.size(), 3u);
  EXPECT_EQ(bins[0].relations, 10);
  EXPECT_NEAR(bins[0].translation_mean, 0.0, 1e-12);
  EXPECT_EQ(bins[1].relations, 10);
  EXPECT_NEAR(bins[1].translation_mean, 0.2, 1e-12);
  EXPECT_NEAR(bins[1].rotation_mean, 0.05, 1e-12);
  EXPECT_NEAR(bins[1].translation_share, 1.0, 1e-12);
  EXPECT_EQ(bins[2].relations, 0);
  EXPECT_TRUE(std::isinf(bins[2].to));
}

TEST(Relations, StampsMatchWithinToleranceOnlyAndOrderDoesNotMatter) {
  std::vector<StampedPose> truth = wiggle(10);
  const std::vector<Relation> relations = relationsOf(truth);
  std::vector<StampedPose> shuffled = truth;
  std::reverse(shuffled.begin(), shuffled.end());   // time going backwards in a log
  for (StampedPose& p : shuffled) p.stamp += 4e-6;  // inside 5 µs
  EXPECT_EQ(evaluateRelations(relations, shuffled, 1e-5).used, 7);
  for (StampedPose& p : shuffled) p.stamp += 1e-3;
  EXPECT_EQ(evaluateRelations(relations, shuffled, 1e-5).used, 0);
}

TEST(Relations, FilesRoundTripAndBadLinesAreNamed) {
  const std::string base = "/tmp/relations_test_" + std::to_string(::getpid());
  const std::vector<StampedPose> truth = wiggle(5);
  ASSERT_EQ(writeTrajectory(base + ".txt", truth), "");
  std::vector<StampedPose> back;
  ASSERT_EQ(readTrajectory(base + ".txt", &back), "");
  ASSERT_EQ(back.size(), truth.size());
  EXPECT_NEAR(back[3].pose.y, truth[3].pose.y, 1e-6);
  {
    std::ofstream bad(base + ".txt");
    bad << "# comment\n1 2 3 4\n5 6 7\n";
  }
  EXPECT_EQ(readTrajectory(base + ".txt", &back), base + ".txt:3: expected 'stamp x y theta'");
  {
    std::ofstream rel(base + ".rel");
    rel << "976052905.167303 976052911.885496 -0.056990 -0.128430 0 0 0 -1.682210\n";
  }
  std::vector<Relation> relations;
  ASSERT_EQ(readRelations(base + ".rel", &relations), "");
  ASSERT_EQ(relations.size(), 1u);
  EXPECT_NEAR(relations[0].motion.theta, -1.682210, 1e-12);
  EXPECT_NE(readRelations("/nonexistent", &relations).find("cannot open"), std::string::npos);
  ::unlink((base + ".txt").c_str());
  ::unlink((base + ".rel").c_str());
}

TEST(Relations, RealRelationFilesParse) {
  const std::string dir = std::string(EKF_SLAM_SOURCE_DIR) + "/../shared/datasets/";
  std::vector<Relation> relations;
  if (readRelations(dir + "intel.relations", &relations) != "") {
    GTEST_SKIP() << "../shared/datasets/intel.relations not found beside the repository";
  }
  EXPECT_EQ(relations.size(), 2984u);
  ASSERT_EQ(readRelations(dir + "aces.relations", &relations), "");
  EXPECT_EQ(relations.size(), 1279u);
}

}  // namespace
}  // namespace ekf_slam
