#include "ekf_slam_core/filter/data_association.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <map>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/sim/landmark_simulator.h"

namespace ekf_slam {
namespace {

PointObservation observed(const Pose2& robot, const Vector2& landmark, double sigma = 0.01) {
  PointObservation obs;
  predictPointObservation(robot, Pose2(), landmark, &obs.z);
  obs.covariance = Matrix2::Identity() * sigma * sigma;
  return obs;
}

TEST(ChiSquare, QuantilesAndBandsMatchTables) {
  EXPECT_NEAR(chiSquareQuantile(0.99, 2), 9.2103, 1e-4);
  EXPECT_NEAR(chiSquareQuantile(0.95, 3), 7.8147, 1e-4);
  const ChiSquareBand band = averageChiSquareBand(3, 30, 0.95);
  EXPECT_NEAR(band.lower, 65.647 / 30, 1e-3);
  EXPECT_NEAR(band.upper, 118.136 / 30, 1e-3);
}

// Two landmarks 1 m apart straight ahead, along the direction in which the
// robot is uncertain (σ = 0.5 m), so that the shift is nearly linear in the
// observation. The robot believes it is 0.6 m further than it is:
// observation 0 (of landmark A) lies nearer to the prediction of B, and
// observation 1 (of B) is outside the gate of A. Nearest neighbour pairs
// observation 0 with B and loses observation 1; JCBB finds that one shift of
// the robot explains both observations together.
class AmbiguousScene : public ::testing::Test {
 protected:
  void SetUp() override {
    FilterOptions options;
    options.tentative_max_age = 0;
    options.motion_noise = MotionNoiseOptions{0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
    filter_ = std::make_unique<EkfSlam>(options);
    a_ = Vector2(6.0, 0.3);
    b_ = Vector2(7.0, 0.3);
    ASSERT_EQ(filter_->augment(observed(Pose2(), a_, 1e-3), &id_a_), FilterStatus::kOk);
    ASSERT_EQ(filter_->augment(observed(Pose2(), b_, 1e-3), &id_b_), FilterStatus::kOk);
    // Believed motion 0.5 m (σ = 0.5 m); true motion −0.1 m.
    ASSERT_EQ(filter_->predict(OdometryControl{0.0, 0.5, 0.0}, 0.1), FilterStatus::kOk);
    const Pose2 truth(-0.1, 0.0, 0.0);
    observations_ = {observed(truth, a_, 0.02), observed(truth, b_, 0.02)};
  }

  std::unique_ptr<EkfSlam> filter_;
  Vector2 a_, b_;
  int id_a_ = -1, id_b_ = -1;
  std::vector<PointObservation> observations_;
};

TEST_F(AmbiguousScene, NearestNeighbourGetsItWrong) {
  AssociationOptions options;
  const AssociationResult result = associate(*filter_, observations_, options);
  ASSERT_EQ(result.observations[0].decision, AssociationDecision::kMatched);
  EXPECT_EQ(result.observations[0].landmark_id, id_b_) << "NN takes the nearer, wrong landmark";
  EXPECT_NE(result.observations[1].decision, AssociationDecision::kMatched);
  // The report explains it: both landmarks were candidates for observation 0.
  ASSERT_EQ(result.observations[0].candidates.size(), 2u);
  EXPECT_EQ(result.observations[0].candidates[0].landmark_id, id_b_);
  EXPECT_LT(result.observations[0].candidates[0].normalised,
            result.observations[0].candidates[1].normalised);
}

TEST_F(AmbiguousScene, JointCompatibilityGetsItRight) {
  AssociationOptions options;
  options.method = AssociationMethod::kJointCompatibility;
  const AssociationResult result = associate(*filter_, observations_, options);
  ASSERT_EQ(result.observations[0].decision, AssociationDecision::kMatched);
  ASSERT_EQ(result.observations[1].decision, AssociationDecision::kMatched);
  EXPECT_EQ(result.observations[0].landmark_id, id_a_);
  EXPECT_EQ(result.observations[1].landmark_id, id_b_);
  EXPECT_GT(result.jcbb_nodes, 0);
  // And the update with JCBB's pairing pulls the robot back to the truth.
  ASSERT_EQ(filter_->update(observations_, result.matches()), FilterStatus::kOk);
  EXPECT_NEAR(filter_->pose().x, -0.1, 0.01);
}

// The ln|S| term decides (thesis §4.2.3): an observation 5 cm from a
// well-known corner (σ 3 cm) and 0.5 m from an uncertain one (σ 0.5 m)
// is nearer the uncertain one by d² alone, since its large S shrinks the
// distance. d² + ln|S| charges it for that uncertainty, and nearest
// neighbour pairs the observation with the well-known corner.
TEST(DataAssociation, TheLogDeterminantTermPrefersTheWellKnownLandmark) {
  FilterOptions options;
  options.tentative_max_age = 0;
  EkfSlam filter(options);
  int known = -1, uncertain = -1;
  ASSERT_EQ(filter.augment(observed(Pose2(), Vector2(1.0, 0.0), 0.03), &known), FilterStatus::kOk);
  ASSERT_EQ(filter.augment(observed(Pose2(), Vector2(1.0, 0.55), 0.5), &uncertain),
            FilterStatus::kOk);
  const AssociationResult result =
      associate(filter, {observed(Pose2(), Vector2(1.0, 0.05), 1e-3)}, AssociationOptions());
  const ObservationAssociation& a = result.observations[0];
  ASSERT_EQ(a.decision, AssociationDecision::kMatched);
  EXPECT_EQ(a.landmark_id, known);
  ASSERT_EQ(a.candidates.size(), 2u) << "both corners inside the gate";
  const AssociationCandidate& first = a.candidates[0];
  const AssociationCandidate& second = a.candidates[1];
  ASSERT_EQ(second.landmark_id, uncertain);
  EXPECT_LT(second.mahalanobis2, first.mahalanobis2) << "d² alone would take the uncertain one";
  EXPECT_LT(first.normalised, second.normalised);
  EXPECT_LT(second.mahalanobis2, result.gate);
  EXPECT_LT(first.mahalanobis2, result.gate);
}

TEST(DataAssociation, BetweenTheGatesIsNeitherMatchedNorNew) {
  FilterOptions options;
  options.tentative_max_age = 0;
  EkfSlam filter(options);
  ASSERT_EQ(filter.augment(observed(Pose2(), Vector2(3.0, 0.0), 0.01)), FilterStatus::kOk);
  AssociationOptions association;
  const double gate = chiSquareQuantile(association.gate_probability, 2);
  const double new_gate = chiSquareQuantile(association.new_landmark_probability, 2);
  // Landmark variance 1e-4 m² plus observation 1e-4 m² along the range: a
  // range offset δ gives d² = δ² / 2e-4.
  auto with_offset = [&](double d2) {
    PointObservation obs = observed(Pose2(), Vector2(3.0, 0.0), 0.01);
    obs.z.range += std::sqrt(d2 * 2e-4);
    return associate(filter, {obs}, association).observations[0];
  };
  EXPECT_EQ(with_offset(0.5 * gate).decision, AssociationDecision::kMatched);
  const ObservationAssociation between = with_offset(0.5 * (gate + new_gate));
  EXPECT_EQ(between.decision, AssociationDecision::kAmbiguous);
  EXPECT_NEAR(between.mahalanobis2, 0.5 * (gate + new_gate), 1e-3);
  EXPECT_EQ(with_offset(1.2 * new_gate).decision, AssociationDecision::kNewLandmark);
}

TEST(DataAssociation, InvalidObservationIsReportedNotMatched) {
  FilterOptions options;
  EkfSlam filter(options);
  ASSERT_EQ(filter.augment(observed(Pose2(), Vector2(3.0, 0.0))), FilterStatus::kOk);
  PointObservation bad = observed(Pose2(), Vector2(3.0, 0.0));
  bad.z.bearing = std::nan("");
  const AssociationResult result = associate(filter, {bad}, AssociationOptions());
  EXPECT_EQ(result.observations[0].decision, AssociationDecision::kInvalid);
  EXPECT_TRUE(result.matches().empty());
  EXPECT_TRUE(result.newLandmarks().empty());
}

// Unknown association on the simulator: the share of matches that pair an
// observation with the landmark it really came from.
double correctPairingRate(AssociationMethod method, int* matches_out, int* duplicates_out) {
  sim::LandmarkSimOptions sim_options;
  sim_options.laps = 2;
  sim::LandmarkSimulator sim(sim_options);
  FilterOptions options;
  options.laser_pose = sim_options.laser_pose;
  EkfSlam filter(options, sim.current().true_pose);
  AssociationOptions association;
  association.method = method;
  std::map<int, int> truth_of_id;
  Pose2 odom = sim.current().odometry;
  int correct = 0, matches = 0;
  while (sim.next()) {
    const sim::SimStep& s = sim.current();
    const IterationReport report =
        runIteration(filter, association, odom, s.odometry, sim_options.dt, s.observations);
    odom = s.odometry;
    EXPECT_TRUE(report.ok());
    for (const PointMatch& m : report.matches) {
      ++matches;
      if (truth_of_id.at(m.landmark_id) == s.true_landmark[m.observation]) ++correct;
    }
    const std::vector<int> fresh = report.association.newLandmarks();
    for (size_t i = 0; i < fresh.size() && i < report.new_landmark_ids.size(); ++i) {
      truth_of_id[report.new_landmark_ids[i]] = s.true_landmark[fresh[i]];
    }
  }
  // Duplicates: two surviving landmarks standing for one true landmark.
  std::map<int, int> count;
  for (const LandmarkInfo& info : filter.landmarks()) ++count[truth_of_id.at(info.id)];
  int duplicates = 0;
  for (const auto& entry : count) duplicates += entry.second - 1;
  *matches_out = matches;
  *duplicates_out = duplicates;
  return matches > 0 ? static_cast<double>(correct) / matches : 0.0;
}

TEST(DataAssociation, NearestNeighbourPairsCorrectlyOnTheSimulator) {
  int matches = 0, duplicates = 0;
  const double rate =
      correctPairingRate(AssociationMethod::kNearestNeighbour, &matches, &duplicates);
  RecordProperty("correct_pairing_rate", std::to_string(rate));
  RecordProperty("matches", matches);
  EXPECT_GT(matches, 1000);
  EXPECT_GE(rate, 0.99);
  EXPECT_EQ(duplicates, 0);
}

TEST(DataAssociation, JointCompatibilityPairsCorrectlyOnTheSimulator) {
  int matches = 0, duplicates = 0;
  const double rate =
      correctPairingRate(AssociationMethod::kJointCompatibility, &matches, &duplicates);
  RecordProperty("correct_pairing_rate", std::to_string(rate));
  EXPECT_GT(matches, 1000);
  EXPECT_GE(rate, 0.99);
  EXPECT_EQ(duplicates, 0);
}

}  // namespace
}  // namespace ekf_slam
