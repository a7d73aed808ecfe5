// MECP association: polygons remembered as their members' ids, matched by
// their centre and then paired as a group; where nearest neighbour pairs a
// corner with the wrong landmark, the group pairs it right.
#include "ekf_slam_core/mecp/mecp_association.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {
namespace {

const Pose2 kLaser(0.1, 0.0, 0.0);

Vector2 polar(double radius, double degrees) {
  const double a = degrees * kPi / 180.0;
  return {radius * std::cos(a), radius * std::sin(a)};
}

PointObservation readingOf(const Pose2& robot, const Vector2& landmark) {
  PointObservation obs;
  EXPECT_TRUE(predictPointObservation(robot, kLaser, landmark, &obs.z));
  obs.covariance = Vector2(0.02 * 0.02, 0.01 * 0.01).asDiagonal();
  return obs;
}

std::vector<PointObservation> scanOf(const Pose2& robot, const std::vector<Vector2>& landmarks) {
  std::vector<PointObservation> scan;
  for (const Vector2& m : landmarks) scan.push_back(readingOf(robot, m));
  return scan;
}

// A filter whose heading grows 0.1 rad less certain (σ) at every
// prediction, even standing still: a robot after a long loop.
EkfSlam uncertainFilter() {
  FilterOptions options;
  options.laser_pose = kLaser;
  options.tentative_max_age = 0;
  options.motion_noise.min_rot_sigma = 0.1;
  return EkfSlam(options, Pose2(), Matrix3::Identity() * 1e-8);
}

// Four corners round the robot, an off-centre quadrilateral.
const std::vector<Vector2> kCorners = {polar(3.0, 40.0), polar(2.6, 130.0), polar(3.2, 225.0),
                                       polar(2.8, 320.0)};

// One scan through the MECP association and the filter, as the pipeline runs it.
IterationReport step(EkfSlam& filter, MecpAssociation& mecp,
                     const std::vector<PointObservation>& scan) {
  IterationReport report;
  observe(filter, AssociationOptions(), scan, &report,
          [&](const EkfSlam& f, const std::vector<PointObservation>& o,
              const AssociationOptions& a) { return mecp.associate(f, o, a, nullptr); });
  mecp.remember(filter, report);
  return report;
}

int landmarkOf(const IterationReport& report, int observation) {
  for (const PointMatch& m : report.matches) {
    if (m.observation == observation) return m.landmark_id;
  }
  return -1;
}

TEST(MecpAssociation, APolygonIsRememberedOnceItsCornersAreLandmarksAndMatchedWhenSeenAgain) {
  EkfSlam filter = uncertainFilter();
  MecpAssociation mecp;
  const IterationReport first = step(filter, mecp, scanOf(Pose2(), kCorners));
  EXPECT_EQ(first.new_landmark_ids.size(), 4u);
  ASSERT_EQ(mecp.polygons().size(), 1u);
  // The remembered list is the landmarks made from the polygon's vertices,
  // counter-clockwise (the corners' own order here).
  std::vector<int> members = mecp.polygons()[0];
  std::rotate(members.begin(), std::min_element(members.begin(), members.end()), members.end());
  EXPECT_EQ(members, first.new_landmark_ids);

  ASSERT_EQ(filter.predict(Pose2(), Pose2(0.1, 0.0, 0.0), 0.1), FilterStatus::kOk);
  const IterationReport second = step(filter, mecp, scanOf(Pose2(0.1, 0.0, 0.0), kCorners));
  EXPECT_EQ(mecp.counters().mecp_polygons, 2);
  EXPECT_EQ(mecp.counters().mecp_group_matches, 1);
  EXPECT_EQ(mecp.counters().mecp_remembered, 1);  // the matched polygon is not stored twice
  EXPECT_EQ(mecp.counters().mecp_pairings_changed, 0);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(landmarkOf(second, i), first.new_landmark_ids[i]);
  EXPECT_LT(mecp.lastScan().group_mahalanobis2, chiSquareQuantile(0.99, 8.0));
}

// Two landmarks mapped earlier (seen singly, never as an enclosing polygon)
// lie 10° clockwise of two of the corners. The robot, its heading 0.14 rad
// uncertain, has in truth turned 10° (0.17 rad) without the odometry
// seeing it: every corner appears 10° clockwise of where the map has it.
// Nearest neighbour pairs those two corners with the decoys (d² near 0
// against about 1.5); the group must fit one heading error for all four
// corners in their order round the robot, and pairs every corner right.
TEST(MecpAssociation, PairsTheCornersAsAGroupWhereNearestNeighbourTakesTheDecoys) {
  EkfSlam filter = uncertainFilter();
  MecpAssociation mecp;
  const IterationReport first = step(filter, mecp, scanOf(Pose2(), kCorners));
  ASSERT_EQ(mecp.polygons().size(), 1u);
  int decoy_a = -1, decoy_b = -1;
  ASSERT_EQ(filter.augment(readingOf(Pose2(), polar(3.0, 30.0)), &decoy_a), FilterStatus::kOk);
  ASSERT_EQ(filter.augment(readingOf(Pose2(), polar(2.6, 120.0)), &decoy_b), FilterStatus::kOk);
  ASSERT_EQ(filter.predict(Pose2(), Pose2(), 0.1), FilterStatus::kOk);  // heading σ now 0.14

  const Pose2 truth(0.0, 0.0, 10.0 * kPi / 180.0);
  const std::vector<PointObservation> scan = scanOf(truth, kCorners);
  const AssociationResult nn = associate(filter, scan, AssociationOptions());
  EXPECT_EQ(nn.observations[0].landmark_id, decoy_a);
  EXPECT_EQ(nn.observations[1].landmark_id, decoy_b);

  const AssociationResult grouped = mecp.associate(filter, scan, AssociationOptions(), nullptr);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(grouped.observations[i].decision, AssociationDecision::kMatched);
    EXPECT_EQ(grouped.observations[i].landmark_id, first.new_landmark_ids[i]) << "corner " << i;
  }
  EXPECT_EQ(mecp.counters().mecp_group_matches, 1);
  EXPECT_EQ(mecp.counters().mecp_pairings_changed, 2);

  // Updated with the group's pairings, the heading moves to the truth;
  // with nearest neighbour's, it stays nearer the decoys' story.
  EkfSlam by_nn = filter;
  EXPECT_EQ(by_nn.update(scan, nn.matches()), FilterStatus::kOk);
  EXPECT_EQ(filter.update(scan, grouped.matches()), FilterStatus::kOk);
  EXPECT_NEAR(filter.pose().theta, truth.theta, 0.01);
  EXPECT_GT(std::abs(by_nn.pose().theta - truth.theta), 0.05);
}

// The same centre but the corners turned 45° about it: the centre fits,
// no ordering of the corners does (a 0.79 rad heading error is 5.6 σ), so
// the point association's decisions stand.
TEST(MecpAssociation, ACentreThatFitsWithCornersThatDoNotIsRefusedByTheGroupGate) {
  EkfSlam filter = uncertainFilter();
  MecpAssociation mecp;
  const std::vector<Vector2> square = {polar(3.0, 45.0), polar(3.0, 135.0), polar(3.0, 225.0),
                                       polar(3.0, 315.0)};
  step(filter, mecp, scanOf(Pose2(), square));
  ASSERT_EQ(filter.predict(Pose2(), Pose2(), 0.1), FilterStatus::kOk);
  const std::vector<PointObservation> turned =
      scanOf(Pose2(), {polar(3.0, 0.0), polar(3.0, 90.0), polar(3.0, 180.0), polar(3.0, 270.0)});
  const AssociationResult nn = associate(filter, turned, AssociationOptions());
  const AssociationResult grouped = mecp.associate(filter, turned, AssociationOptions(), nullptr);
  EXPECT_EQ(mecp.counters().mecp_group_refused, 1);
  EXPECT_EQ(mecp.counters().mecp_group_matches, 0);
  EXPECT_TRUE(mecp.lastScan().member_ids.empty());
  ASSERT_EQ(grouped.observations.size(), nn.observations.size());
  for (size_t i = 0; i < nn.observations.size(); ++i) {
    EXPECT_EQ(grouped.observations[i].decision, nn.observations[i].decision);
    EXPECT_EQ(grouped.observations[i].landmark_id, nn.observations[i].landmark_id);
  }
}

TEST(MecpAssociation, APolygonWithAMemberGoneIsNeitherMatchedNorKept) {
  EkfSlam filter = uncertainFilter();
  MecpAssociation mecp;
  const IterationReport first = step(filter, mecp, scanOf(Pose2(), kCorners));
  ASSERT_TRUE(filter.removeLandmark(first.new_landmark_ids[2]));
  ASSERT_EQ(filter.predict(Pose2(), Pose2(), 0.1), FilterStatus::kOk);
  const IterationReport second = step(filter, mecp, scanOf(Pose2(), kCorners));
  EXPECT_EQ(mecp.counters().mecp_group_matches, 0);
  // The corner whose landmark went is mapped anew, the polygon remembered
  // anew with it, and the old list forgotten.
  ASSERT_EQ(second.new_landmark_ids.size(), 1u);
  ASSERT_EQ(mecp.polygons().size(), 1u);
  EXPECT_NE(
      std::find(mecp.polygons()[0].begin(), mecp.polygons()[0].end(), second.new_landmark_ids[0]),
      mecp.polygons()[0].end());
}

TEST(MecpAssociation, TooFewOrNonFiniteReadingsGiveNoPolygon) {
  EkfSlam filter = uncertainFilter();
  MecpAssociation mecp;
  std::vector<PointObservation> scan = scanOf(Pose2(), {kCorners[0], kCorners[1]});
  EXPECT_TRUE(observedPolygon(scan, kLaser).empty());
  scan = scanOf(Pose2(), kCorners);
  scan[1].z.range = std::nan("");
  // Three corners left: they still enclose the robot or they do not; the
  // NaN one is never a vertex.
  for (int v : observedPolygon(scan, kLaser)) EXPECT_NE(v, 1);
  const AssociationResult result = mecp.associate(filter, scan, AssociationOptions(), nullptr);
  EXPECT_EQ(result.observations[1].decision, AssociationDecision::kInvalid);
}

TEST(JointMahalanobis, OnePairingEqualsTheIndividualDistanceAndBadPairingsAreInfinite) {
  EkfSlam filter = uncertainFilter();
  std::vector<PointObservation> scan = scanOf(Pose2(), kCorners);
  int id = -1;
  ASSERT_EQ(filter.augment(scan[0], &id), FilterStatus::kOk);
  ASSERT_EQ(filter.predict(Pose2(), Pose2(), 0.1), FilterStatus::kOk);
  scan[0].z.bearing += 0.05;
  const AssociationResult nn = associate(filter, scan, AssociationOptions());
  ASSERT_EQ(nn.observations[0].landmark_id, id);
  EXPECT_NEAR(jointMahalanobis2(filter, scan, {{0, id}}), nn.observations[0].mahalanobis2, 1e-9);
  EXPECT_EQ(jointMahalanobis2(filter, scan, {}), 0.0);
  EXPECT_TRUE(std::isinf(jointMahalanobis2(filter, scan, {{0, id + 7}})));
  EXPECT_TRUE(std::isinf(jointMahalanobis2(filter, scan, {{9, id}})));
}

}  // namespace
}  // namespace ekf_slam
