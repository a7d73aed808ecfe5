#include "ekf_slam_core/pipeline/line_landmarks.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <iostream>
#include <limits>

#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_core/sim/drive.h"

namespace ekf_slam {
namespace {

const LandmarkSet kLineSets[] = {LandmarkSet::kPointsAndLines, LandmarkSet::kPointsAndLineAngles};

PipelineOptions lineOptions(LandmarkSet set, const Pose2& laser) {
  PipelineOptions options;
  options.filter.laser_pose = laser;
  options.scan_matching.enabled = false;
  options.loop_closure.enabled = false;  // features are fed without scans below
  options.landmarks = set;
  return options;
}

int lineLandmarkCount(const EkfSlam& filter) {
  int count = 0;
  for (const LandmarkInfo& info : filter.landmarks()) count += info.kind != LandmarkKind::kPoint;
  return count;
}

// The wall segment from a to b (laser frame) as the extractor reports it.
LineFeature segment(const Vector2& a, const Vector2& b) {
  LineFeature line;
  const Vector2 u = (b - a).normalized();
  Vector2 n(-u.y(), u.x());
  if (n.dot(a) < 0.0) n = -n;
  line.p = n.dot(a);
  line.theta = std::atan2(n.y(), n.x());
  line.covariance << 1e-4, 0.0, 0.0, 1e-5;
  line.start = a;
  line.end = b;
  line.num_points = 50;
  return line;
}

double minEigenvalue(const Eigen::MatrixXd& P) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues().minCoeff();
}

// The simulated drive among walls and cartons: walls become line landmarks
// that are re-observed scan after scan, every landmark has its extent, and
// the estimate stays as good as with points alone.
TEST(LineLandmarks, WallsAreAssociatedAndAugmentedAlongADrive) {
  sim::DriveOptions drive_options;
  drive_options.start =
      Pose2(sim::kMixedDriveStartX, sim::kMixedDriveStartY, sim::kMixedDriveStartYaw);
  drive_options.laser = Pose2(0.16, 0.0, 0.0);
  drive_options.seed = 4;
  const sim::PolygonWorld world = sim::roomWithCartons();
  const sim::SimulatedDrive drive = sim::simulateDrive(world, sim::mixedDrive(), drive_options);
  for (LandmarkSet set : kLineSets) {
    SCOPED_TRACE(toString(set));
    SlamPipeline pipeline(lineOptions(set, drive_options.laser));
    for (size_t i = 0; i < drive.scans.size(); ++i) {
      pipeline.processScan(drive.scans[i], drive.odometry[i]);
    }
    const PipelineCounters& c = pipeline.counters();
    std::cout << toString(set) << ": " << c.line_observations << " segments, " << c.line_matches
              << " matched, " << c.new_line_landmarks << " new, " << c.line_ambiguous
              << " ambiguous, average NIS " << c.line_nis_sum / std::max<long>(c.line_matches, 1)
              << "\n";
    EXPECT_GT(c.new_line_landmarks, 0);
    // Nearly every sighting of a wall is a match, not a new landmark.
    EXPECT_GT(c.line_matches, 20 * c.new_line_landmarks);
    EXPECT_EQ(c.lines_refused, 0);
    EXPECT_EQ(c.line_update_failures, 0);
    const EkfSlam& filter = pipeline.filter();
    const int lines = lineLandmarkCount(filter);
    EXPECT_GE(lines, 4);   // the room's walls at least …
    EXPECT_LE(lines, 12);  // … and not a landmark per sighting
    ASSERT_EQ(static_cast<int>(pipeline.lineSupport().size()), lines);

    // θ-only walls get the corners at their ends as endpoints.
    int with_endpoints = 0;
    for (const auto& entry : pipeline.lineSupport()) {
      with_endpoints += entry.second.endpoint_ids[0] >= 0 || entry.second.endpoint_ids[1] >= 0;
    }
    if (set == LandmarkSet::kPointsAndLineAngles) EXPECT_GE(with_endpoints, 2);
    if (set == LandmarkSet::kPointsAndLines) EXPECT_EQ(with_endpoints, 0);

    // Every line landmark lies on a wall of the world over its seen extent.
    const Pose2 world_from_map = drive.truth.front();
    for (const auto& [id, support] : pipeline.lineSupport()) {
      const int slot = filter.slotOf(id);
      ASSERT_GE(slot, 0);
      EXPECT_GT(support.s_max - support.s_min, 0.5);
      const double theta = filter.landmarkKind(slot) == LandmarkKind::kLine
                               ? filter.lineLandmark(slot).theta
                               : filter.lineAngle(slot);
      if (filter.landmarkKind(slot) != LandmarkKind::kLine) continue;
      const Vector2 n(std::cos(theta), std::sin(theta)), d(-n.y(), n.x());
      const double p = filter.lineLandmark(slot).p;
      for (double s : {support.s_min, support.s_max}) {
        const Vector2 q = transformFrom(world_from_map, p * n + s * d);
        double nearest = std::numeric_limits<double>::infinity();
        for (const sim::Segment& wall : world.segments()) {
          const Vector2 w = wall.b - wall.a;
          const double t = std::clamp((q - wall.a).dot(w) / w.squaredNorm(), 0.0, 1.0);
          nearest = std::min(nearest, (wall.a + t * w - q).norm());
        }
        EXPECT_LT(nearest, 0.1) << "line " << id << " end at s = " << s;
      }
    }
    const Pose2 truth = between(drive.truth.front(), drive.truth.back());
    EXPECT_LT((filter.pose().translation() - truth.translation()).norm(), 0.1);
    const Eigen::MatrixXd P = filter.covariance();
    EXPECT_TRUE(P.allFinite());
    EXPECT_GT(minEigenvalue(P), -1e-9);
  }
}

// Two collinear walls in different rooms: the second one is seen where the
// first was never seen, so it becomes a landmark of its own instead of
// dragging the robot onto the first.
TEST(LineLandmarks, CollinearWallsOutsideTheSeenExtentStayApart) {
  for (LandmarkSet set : kLineSets) {
    SCOPED_TRACE(toString(set));
    PipelineOptions options = lineOptions(set, Pose2());
    SlamPipeline pipeline(options);
    // The robot drives along x; a wall at y = 2 from x = 0 to 3 (map frame)
    // is in view while the robot is at x <= 1, another on the same line
    // from x = 8 to 11 once the robot is at x >= 7.
    for (int k = 0; k <= 20; ++k) {
      const double x = 0.5 * k;
      FeatureSet features;
      if (x <= 1.0) features.lines.push_back(segment({0.0 - x, 2.0}, {3.0 - x, 2.0}));
      if (x >= 7.0) features.lines.push_back(segment({8.0 - x, 2.0}, {11.0 - x, 2.0}));
      pipeline.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
    }
    EXPECT_EQ(lineLandmarkCount(pipeline.filter()), 2);
    EXPECT_EQ(pipeline.counters().new_line_landmarks, 2);
    EXPECT_GT(pipeline.counters().line_matches, 5);
    ASSERT_EQ(pipeline.lineSupport().size(), 2u);
    for (const auto& [id, support] : pipeline.lineSupport()) {
      EXPECT_NEAR(support.s_max - support.s_min, 3.0, 1e-6) << "line " << id;
    }

    // With a margin wider than the gap the second wall is taken for the first.
    options.lines.overlap_margin = 6.0;
    SlamPipeline merged(options);
    for (int k = 0; k <= 20; ++k) {
      const double x = 0.5 * k;
      FeatureSet features;
      if (x <= 1.0) features.lines.push_back(segment({0.0 - x, 2.0}, {3.0 - x, 2.0}));
      if (x >= 7.0) features.lines.push_back(segment({8.0 - x, 2.0}, {11.0 - x, 2.0}));
      merged.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
    }
    EXPECT_EQ(lineLandmarkCount(merged.filter()), 1);
  }
}

// A map saved with its lines and loaded into a new pipeline: the lines
// keep their extents, so a collinear wall beyond them stays a wall of its own.
TEST(LineLandmarks, ExtentsSurviveAMapFileRoundTrip) {
  const PipelineOptions options = lineOptions(LandmarkSet::kPointsAndLines, Pose2());
  SlamPipeline first(options);
  for (int k = 0; k <= 2; ++k) {
    const double x = 0.5 * k;
    FeatureSet features;
    features.lines.push_back(segment({0.0 - x, 2.0}, {3.0 - x, 2.0}));
    first.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
  }
  ASSERT_EQ(first.lineSupport().size(), 1u);
  const LandmarkMapFile map = toLandmarkMapFile(first.filter(), first.lineSupport(), "map");

  // The new run starts where the map puts it: at x = 7, from where only
  // the second wall, from x = 8 to 11, is in view.
  PipelineOptions relocated = options;
  relocated.initial_pose = Pose2(7.0, 0.0, 0.0);
  relocated.initial_pose_covariance = Matrix3::Identity() * 1e-6;
  SlamPipeline second(relocated);
  std::unordered_map<int, LineSupport> support;
  ASSERT_EQ(seedFilter(map, &second.mutableFilter(), &support), 0);
  second.seedLineSupport(support);
  ASSERT_EQ(second.lineSupport().size(), 1u);
  const LineSupport& before = first.lineSupport().begin()->second;
  const LineSupport& after = second.lineSupport().begin()->second;
  EXPECT_NEAR(after.s_min, before.s_min, 1e-9);
  EXPECT_NEAR(after.s_max, before.s_max, 1e-9);

  for (int k = 0; k <= 6; ++k) {
    const double x = 7.0 + 0.5 * k;
    FeatureSet features;
    features.lines.push_back(segment({8.0 - x, 2.0}, {11.0 - x, 2.0}));
    second.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
  }
  EXPECT_EQ(lineLandmarkCount(second.filter()), 2);
}

// A wall seen end-on: its line passes through the laser (p = 0), the beams
// graze it. Neither augmenting nor updating may break the filter.
TEST(LineLandmarks, AWallSeenEndOnLeavesAValidFilter) {
  for (LandmarkSet set : kLineSets) {
    SCOPED_TRACE(toString(set));
    SlamPipeline pipeline(lineOptions(set, Pose2(0.1, 0.0, 0.0)));
    for (int k = 0; k < 10; ++k) {
      const double x = 0.1 * k;
      FeatureSet features;
      // The wall y = 0 ahead of the robot, in the laser frame at (x + 0.1, 0).
      features.lines.push_back(segment({2.0 - x, 0.0}, {5.0 - x, 0.0}));
      // And one across, to have some ordinary line as well.
      features.lines.push_back(segment({4.0 - x, -1.5}, {4.0 - x, 1.5}));
      const ScanResult r = pipeline.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
      EXPECT_EQ(r.outcome, ScanOutcome::kIterated);
      EXPECT_EQ(r.lines.update_status, FilterStatus::kOk);
    }
    const EkfSlam& filter = pipeline.filter();
    EXPECT_EQ(lineLandmarkCount(filter), 2);
    EXPECT_TRUE(filter.state().allFinite());
    const Eigen::MatrixXd P = filter.covariance();
    EXPECT_TRUE(P.allFinite());
    EXPECT_GT(minEigenvalue(P), -1e-12);
    EXPECT_NEAR(filter.pose().x, 0.9, 1e-3);
    EXPECT_NEAR(filter.pose().y, 0.0, 1e-3);
  }
}

// A corner at a wall's end seen once (tentative) becomes an endpoint of a
// θ-only wall and is pruned in the scan that gives the wall's other end: the
// wall forgets the pruned corner and takes the new one, and nothing reads a
// landmark that has left the filter.
TEST(LineLandmarks, AnEndpointPrunedInTheSameScanIsForgotten) {
  PipelineOptions options = lineOptions(LandmarkSet::kPointsAndLineAngles, Pose2());
  options.filter.tentative_max_age = 3;
  SlamPipeline pipeline(options);
  // The robot drives along x beside the wall y = 2, x from 0.5 to 4.5 (map
  // frame); the corner at x = 0.5 is seen in the first scan only, the
  // corner at x = 4.5 in the scan at which the first is pruned.
  auto corner = [](const Vector2& at) {
    PointFeature point;
    point.kind = PointKind::kCorner;
    point.landmark_candidate = true;
    point.position = at;
    point.range = at.norm();
    point.bearing = std::atan2(at.y(), at.x());
    point.range_bearing_covariance << 1e-4, 0.0, 0.0, 1e-5;
    point.line = 0;
    return point;
  };
  int first_corner = -1, second_corner = -1;
  for (int k = 0; k <= options.filter.tentative_max_age; ++k) {
    const double x = 0.05 * k;
    FeatureSet features;
    features.lines.push_back(segment({0.5 - x, 2.0}, {4.5 - x, 2.0}));
    if (k == 0) features.points_of_interest.push_back(corner({0.5 - x, 2.0}));
    if (k == options.filter.tentative_max_age) {
      features.points_of_interest.push_back(corner({4.5 - x, 2.0}));
    }
    const ScanResult r = pipeline.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
    ASSERT_EQ(r.outcome, ScanOutcome::kIterated);
    if (k == 0) {
      ASSERT_EQ(r.iteration.new_landmark_ids.size(), 1u);
      first_corner = r.iteration.new_landmark_ids[0];
      ASSERT_EQ(pipeline.lineSupport().size(), 1u);
      EXPECT_EQ(pipeline.lineSupport().begin()->second.endpoint_ids[0], first_corner);
    }
    if (k == options.filter.tentative_max_age) {
      ASSERT_EQ(r.iteration.new_landmark_ids.size(), 1u);
      second_corner = r.iteration.new_landmark_ids[0];
      EXPECT_EQ(r.iteration.pruned, 1);
      EXPECT_EQ(r.lines.matches.size(), 1u);
    }
  }
  const EkfSlam& filter = pipeline.filter();
  EXPECT_LT(filter.slotOf(first_corner), 0);
  ASSERT_EQ(pipeline.lineSupport().size(), 1u);
  const LineSupport& wall = pipeline.lineSupport().begin()->second;
  for (int e : wall.endpoint_ids) EXPECT_TRUE(e == -1 || e == second_corner) << e;
  EXPECT_TRUE(wall.endpoint_ids[0] == second_corner || wall.endpoint_ids[1] == second_corner);
  EXPECT_TRUE(filter.state().allFinite());
}

// A segment whose value or covariance is not finite is refused and
// counted; the filter ends exactly where it ends without that segment.
TEST(LineLandmarks, NonFiniteLinesAreRefusedCountedAndLeaveTheMapUnchanged) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (LandmarkSet set : kLineSets) {
    SCOPED_TRACE(toString(set));
    SlamPipeline clean(lineOptions(set, Pose2()));
    SlamPipeline dirty(lineOptions(set, Pose2()));
    for (int k = 0; k < 5; ++k) {
      const double x = 0.2 * k;
      FeatureSet features;
      features.lines.push_back(segment({1.0 - x, 2.0}, {4.0 - x, 2.0}));
      clean.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
      LineFeature bad = segment({3.0 - x, -1.0}, {3.0 - x, 1.5});
      bad.covariance(0, 1) = bad.covariance(1, 0) = k % 2 == 0 ? nan : bad.covariance(0, 1);
      if (k % 2 == 1) bad.theta = std::numeric_limits<double>::infinity();
      features.lines.push_back(bad);
      dirty.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
    }
    EXPECT_EQ(clean.counters().lines_refused, 0);
    EXPECT_EQ(dirty.counters().lines_refused, 5);
    EXPECT_EQ(dirty.filter().stateDim(), clean.filter().stateDim());
    EXPECT_EQ(dirty.filter().state(), clean.filter().state());
    EXPECT_EQ(dirty.filter().covariance(), clean.filter().covariance());
  }
}

// points+mecp: four corners around the robot (a laser that sees all
// round) enclose it; the first scan's polygon is remembered and every later
// scan's is matched to it, its corners paired as a group. The pairings are
// the points' own here (nothing to correct), so the filter ends as with
// the points alone: the MECP adds no second update of the same readings.
TEST(MecpInThePipeline, CornersAroundTheRobotAreRememberedAndMatchedAsOnePolygon) {
  auto run = [](LandmarkSet set) {
    PipelineOptions options = lineOptions(set, Pose2());
    SlamPipeline pipeline(options);
    for (int k = 0; k < 6; ++k) {
      const double x = 0.05 * k;
      FeatureSet features;
      for (const Vector2& corner :
           {Vector2(2.0, 1.5), Vector2(-1.5, 2.0), Vector2(-2.0, -1.5), Vector2(1.5, -2.0)}) {
        PointFeature point;
        point.landmark_candidate = true;
        point.position = corner - Vector2(x, 0.0);
        point.range = point.position.norm();
        point.bearing = std::atan2(point.position.y(), point.position.x());
        point.range_bearing_covariance = Vector2(1e-4, 1e-5).asDiagonal();
        point.covariance = Matrix2::Identity() * 1e-4;
        features.points_of_interest.push_back(point);
      }
      pipeline.processFeatures(0.1 * (k + 1), features, Pose2(x, 0.0, 0.0));
    }
    return std::make_pair(pipeline.counters(), pipeline.filter().covariance());
  };
  const auto [mecp_counters, mecp_covariance] = run(LandmarkSet::kPointsAndMecp);
  const auto [point_counters, point_covariance] = run(LandmarkSet::kPoints);
  EXPECT_EQ(mecp_counters.mecp_polygons, 6);
  EXPECT_EQ(mecp_counters.mecp_remembered, 1);
  EXPECT_EQ(mecp_counters.mecp_group_matches, 5);  // every scan after the first
  EXPECT_EQ(mecp_counters.mecp_pairings_changed, 0);
  EXPECT_EQ(point_counters.mecp_polygons, 0);
  EXPECT_EQ(mecp_counters.matches, point_counters.matches);
  EXPECT_EQ(mecp_covariance, point_covariance);
}

// The loop MECP association closes and nearest neighbour misses: four
// corners of a room about 4 m round its centre, seen only from within
// 0.6 m of it (the room's walls hide them from the corridor), and four more
// features where the odometry's error will carry the corners. The robot
// drives 3 m out along the corridor, turns round (its odometry reports 5°
// less turn than it made: a wheel slipped, 1.9 σ of the turn's noise) and
// drives back into the room. Returning, it sees each corner where its
// dead-reckoned pose expects one of the other four: nearest neighbour
// pairs the corners with those (d² near 0 against about 3), maps the other
// four anew, and keeps its 0.26 m error; the room's polygon, remembered at
// the start, pairs its corners with their own landmarks and the pose comes
// back to the truth.
TEST(MecpInThePipeline, ClosesTheLoopThatNearestNeighbourMisses) {
  const double slip = 5.0 * kPi / 180.0;
  std::vector<Pose2> truth, odometry;  // per scan
  Pose2 t(0.0, 0.0, 0.0), o(0.0, 0.0, 0.0);
  auto move = [&](const Pose2& true_step, const Pose2& reported_step, int n) {
    for (int k = 0; k < n; ++k) {
      t = compose(t, true_step);
      o = compose(o, reported_step);
      truth.push_back(t);
      odometry.push_back(o);
    }
  };
  move(Pose2(), Pose2(), 5);
  move(Pose2(0.1, 0.0, 0.0), Pose2(0.1, 0.0, 0.0), 30);
  move(Pose2(0.0, 0.0, kPi / 18), Pose2(0.0, 0.0, (kPi - slip) / 18), 18);
  const size_t returning = truth.size();
  move(Pose2(0.1, 0.0, 0.0), Pose2(0.1, 0.0, 0.0), 30);
  move(Pose2(0.0, 0.0, kPi / 18), Pose2(0.0, 0.0, kPi / 18), 18);
  move(Pose2(), Pose2(), 5);
  // The map frame is the first pose; nothing is seen between the room
  // visits, so on return the estimate is the odometry's and E (constant
  // after the turn) maps where a point truly is to where the filter puts it.
  const Pose2 E = compose(odometry[returning], inverse(truth[returning]));
  std::vector<Vector2> world = {{3.2, 2.6}, {-2.9, 3.0}, {-3.1, -2.7}, {2.8, -3.2}};
  for (int i = 0; i < 4; ++i) world.push_back(transformFrom(E, world[i]));

  auto run = [&](LandmarkSet set) {
    PipelineOptions options = lineOptions(set, Pose2());
    MotionNoiseOptions& noise = options.filter.motion_noise;
    noise = MotionNoiseOptions();
    noise.rot_per_rot = noise.rot_per_trans = noise.trans_per_trans = noise.trans_per_rot = 0.0;
    noise.rot_per_radian = 0.045 * 0.045 / kPi;  // σ 0.045 rad per half turn
    noise.rot_per_metre = 1e-4;
    noise.trans_per_metre = 1e-3;
    SlamPipeline pipeline(options);
    std::vector<double> errors;
    for (size_t k = 0; k < truth.size(); ++k) {
      FeatureSet features;
      if (truth[k].translation().norm() < 0.6) {
        for (const Vector2& m : world) {
          PointFeature point;
          point.landmark_candidate = true;
          point.position = transformTo(truth[k], m);
          point.range = point.position.norm();
          point.bearing = std::atan2(point.position.y(), point.position.x());
          point.range_bearing_covariance = Vector2(1e-4, 1e-4).asDiagonal();
          point.covariance = Matrix2::Identity() * 1e-4;
          features.points_of_interest.push_back(point);
        }
      }
      pipeline.processFeatures(0.2 * (k + 1), features, odometry[k]);
      errors.push_back((pipeline.filter().pose().translation() - truth[k].translation()).norm());
    }
    return std::make_pair(pipeline.counters(), errors);
  };
  const auto [mecp, mecp_errors] = run(LandmarkSet::kPointsAndMecp);
  const auto [nn, nn_errors] = run(LandmarkSet::kPoints);
  // Just before the room comes back into sight, both carry the slip's error.
  const size_t before_sight = returning + 22;  // 0.7 m from the centre
  EXPECT_GT(nn_errors[before_sight], 0.2);
  EXPECT_NEAR(mecp_errors[before_sight], nn_errors[before_sight], 1e-9);
  EXPECT_GT(nn_errors.back(), 0.2);
  EXPECT_EQ(nn.new_landmarks, 12);  // the eight, and four again on return
  EXPECT_LT(mecp_errors.back(), 0.01);
  EXPECT_EQ(mecp.new_landmarks, 8);
  EXPECT_GE(mecp.mecp_pairings_changed, 4);
  EXPECT_EQ(mecp.mecp_group_refused, 0);
}

// Two rooms joined by a door, the robot driving from one into the other:
// the walls it maps give a doorway and two rooms, and the corners of each
// room carry that room's label, so that no association pairs across the
// dividing wall. The estimate is as good as without the gate.
TEST(RoomGatingInThePipeline, MappedWallsGiveTwoRoomsAndTheirCornersTheirLabels) {
  sim::PolygonWorld world;
  world.addPolygon({{-4.0, -2.5}, {4.0, -2.5}, {4.0, 2.5}, {-4.0, 2.5}});
  world.addSegment({0.0, -2.5}, {0.0, -0.45});  // the dividing wall, a 0.9 m door in it
  world.addSegment({0.0, 0.45}, {0.0, 2.5});
  world.addBox({-2.5, 1.5}, 0.4, 0.4);  // cartons: corners in each room
  world.addBox({2.5, -1.5}, 0.4, 0.4);
  sim::DriveOptions drive_options;
  drive_options.start = Pose2(-3.2, 0.0, 0.0);
  drive_options.laser = Pose2(0.16, 0.0, 0.0);
  drive_options.seed = 3;
  // Through the door, turn round, and back into the first room.
  const std::vector<sim::DriveSegment> segments = {
      {0.3, 0.0, 20.0}, {0.0, 0.5, kPi / 0.5}, {0.3, 0.0, 14.0}, {0.0, 0.5, kPi / 0.5}};
  const sim::SimulatedDrive drive = sim::simulateDrive(world, segments, drive_options);
  const Pose2 world_from_map = drive.truth.front();
  const Pose2 truth = between(drive.truth.front(), drive.truth.back());
  double error[2] = {0.0, 0.0};
  for (bool gated : {false, true}) {
    SCOPED_TRACE(gated ? "gated" : "not gated");
    PipelineOptions options = lineOptions(LandmarkSet::kPointsAndLines, drive_options.laser);
    options.rooms.enabled = gated;
    ASSERT_EQ(options.validate(), "");
    SlamPipeline pipeline(options);
    for (size_t i = 0; i < drive.scans.size(); ++i) {
      pipeline.processScan(drive.scans[i], drive.odometry[i]);
    }
    const EkfSlam& filter = pipeline.filter();
    error[gated] = (filter.pose().translation() - truth.translation()).norm();
    if (!gated) {
      EXPECT_EQ(pipeline.roomGate(), nullptr);
      continue;
    }
    const PipelineCounters& c = pipeline.counters();
    EXPECT_GT(c.room_rebuilds, 10);
    EXPECT_GE(c.doorways, 1);
    EXPECT_GE(c.rooms, 2);
    const RoomGate* gate = pipeline.roomGate();
    ASSERT_NE(gate, nullptr);
    // Corners well inside each room: one label per room, the two differ.
    std::vector<int> left, right;
    for (const LandmarkInfo& info : filter.landmarks()) {
      if (info.kind != LandmarkKind::kPoint) continue;
      const Vector2 at =
          transformFrom(world_from_map, filter.landmarkPosition(filter.slotOf(info.id)));
      const std::vector<int> rooms = gate->landmarkRooms(info.id);
      if (std::abs(at.x()) < 0.5 || rooms.size() != 1) continue;
      (at.x() < 0.0 ? left : right).push_back(rooms.front());
    }
    std::cout << c.room_rebuilds << " rebuilds, " << c.rooms << " rooms, " << c.doorways
              << " doorways; corners labelled " << left.size() << " left, " << right.size()
              << " right; pose error " << error[false] << " m without the gate, " << error[true]
              << " m with it\n";
    ASSERT_GE(left.size(), 2u);
    ASSERT_GE(right.size(), 2u);
    for (int room : left) EXPECT_EQ(room, left.front());
    for (int room : right) EXPECT_EQ(room, right.front());
    EXPECT_NE(left.front(), right.front());
  }
  EXPECT_LT(error[true], 0.1);
  EXPECT_LT(error[true], error[false] + 0.02);
}

TEST(LineLandmarks, TheLandmarkSettingIsValidated) {
  PipelineOptions options;
  EXPECT_EQ(options.landmarks, LandmarkSet::kPoints);
  for (LandmarkSet set : kLineSets) {
    options.landmarks = set;
    EXPECT_EQ(options.validate(), "");
  }
  options.landmarks = static_cast<LandmarkSet>(7);
  const std::string error = options.validate();
  EXPECT_NE(error.find("landmarks"), std::string::npos) << error;
  EXPECT_NE(error.find("points, points+lines, points+lines_theta, points+mecp"), std::string::npos)
      << error;
  options.landmarks = LandmarkSet::kPointsAndLines;
  options.lines.min_length = -1.0;
  EXPECT_NE(options.validate().find("lines.min_length"), std::string::npos) << options.validate();
  options.lines.min_length = 1.0;
  options.lines.max_range = 0.0;
  EXPECT_NE(options.validate().find("lines.max_range"), std::string::npos) << options.validate();
}

}  // namespace
}  // namespace ekf_slam
