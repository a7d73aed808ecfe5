// The filter's landmarks of every kind through the map file and back:
// save_map then load_map gives the same landmarks, and what cannot be
// loaded again is never written.
#include "ekf_slam_core/pipeline/map_file_conversion.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>

namespace ekf_slam {
namespace {

// A filter after a few steps with two corner points, a (p, θ) wall and a
// θ-only wall between the corners, all correlated through the pose.
struct MixedFilter {
  EkfSlam filter;
  int corner_ids[2] = {-1, -1};
  int line_id = -1, angle_id = -1;
};

MixedFilter mixedFilter() {
  FilterOptions options;
  options.laser_pose = Pose2(0.16, 0.0, 0.0);
  options.tentative_max_age = 0;
  MixedFilter m{EkfSlam(options, Pose2(0.5, -0.2, 0.3), Matrix3::Identity() * 1e-3)};
  EkfSlam& filter = m.filter;
  const Vector2 corners[2] = {{6.0, -3.0}, {6.0, 4.0}};
  const PolarLine wall_through_corners{6.0, 0.0}, far_wall{5.0, 0.5 * kPi};
  const Matrix2 point_noise = Matrix2(Vector2(4e-4, 1e-4).asDiagonal());
  const Matrix2 line_noise = Matrix2(Vector2(4e-4, 1e-4).asDiagonal());
  auto pointObservation = [&](const Vector2& q) {
    const Vector2 d = transformTo(compose(filter.pose(), options.laser_pose), q);
    return PointObservation{RangeBearing{d.norm(), std::atan2(d.y(), d.x())}, point_noise};
  };
  auto lineObservation = [&](const PolarLine& wall) {
    LineObservation z;
    EXPECT_TRUE(predictLineObservation(filter.pose(), options.laser_pose, wall, &z.z));
    z.covariance = line_noise;
    return z;
  };
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(filter.augment(pointObservation(corners[k]), &m.corner_ids[k]), FilterStatus::kOk);
  }
  EXPECT_EQ(filter.augmentLine(lineObservation(far_wall), LandmarkKind::kLine, &m.line_id),
            FilterStatus::kOk);
  EXPECT_EQ(filter.augmentLine(lineObservation(wall_through_corners), LandmarkKind::kLineAngle,
                               &m.angle_id),
            FilterStatus::kOk);
  Pose2 odometry;
  for (int step = 0; step < 3; ++step) {
    const Pose2 next = compose(odometry, Pose2(0.2, 0.0, 0.05));
    EXPECT_EQ(filter.predict(odometry, next, 0.2), FilterStatus::kOk);
    odometry = next;
    EXPECT_EQ(filter.update({pointObservation(corners[0]), pointObservation(corners[1])},
                            {{0, m.corner_ids[0]}, {1, m.corner_ids[1]}}),
              FilterStatus::kOk);
    LineMatch line, angle;
    line.observation = 0;
    line.landmark_id = m.line_id;
    angle.observation = 1;
    angle.landmark_id = m.angle_id;
    angle.endpoint_ids[0] = m.corner_ids[0];
    angle.endpoint_ids[1] = m.corner_ids[1];
    EXPECT_EQ(filter.updateLines({lineObservation(far_wall), lineObservation(wall_through_corners)},
                                 {line, angle}),
              FilterStatus::kOk);
  }
  return m;
}

std::unordered_map<int, LineSupport> supportOf(const MixedFilter& m) {
  std::unordered_map<int, LineSupport> support;
  support[m.line_id].s_min = -2.5;
  support[m.line_id].s_max = 4.25;
  support[m.angle_id].s_min = -3.0;
  support[m.angle_id].s_max = 4.0;
  support[m.angle_id].endpoint_ids[0] = m.corner_ids[0];
  support[m.angle_id].endpoint_ids[1] = m.corner_ids[1];
  return support;
}

TEST(MapFileConversion, SaveThenLoadGivesTheSameLandmarksOfEveryKind) {
  const MixedFilter m = mixedFilter();
  const EkfSlam& saved = m.filter;
  const LandmarkMapFile file = toLandmarkMapFile(saved, supportOf(m), "map");
  EXPECT_EQ(file.landmarks.size(), 2u);
  EXPECT_EQ(file.lines.size(), 1u);
  EXPECT_EQ(file.line_angles.size(), 1u);

  char path[] = "/tmp/map_file_conversion_testXXXXXX";
  const int fd = ::mkstemp(path);
  ASSERT_GE(fd, 0);
  ::close(fd);
  ASSERT_EQ(writeLandmarkMap(path, file), "");
  LandmarkMapFile read;
  ASSERT_EQ(readLandmarkMap(path, &read), "");
  std::remove(path);

  // Loading into a fresh filter, as ~load_map does before the first scan.
  EkfSlam loaded(saved.options());
  std::unordered_map<int, LineSupport> support;
  ASSERT_EQ(seedFilter(read, &loaded, &support), 0);
  ASSERT_EQ(loaded.landmarkCount(), saved.landmarkCount());
  for (int s = 0; s < saved.landmarkCount(); ++s) {
    const LandmarkInfo& info = saved.landmarks()[s];
    const int t = loaded.slotOf(info.id);
    ASSERT_GE(t, 0) << info.id;
    ASSERT_EQ(loaded.landmarkKind(t), info.kind) << info.id;
    EXPECT_EQ(loaded.landmarks()[t].observations, info.observations);
    EXPECT_GT(info.observations, 1);
    switch (info.kind) {
      case LandmarkKind::kPoint:
        EXPECT_EQ(loaded.landmarkPosition(t), saved.landmarkPosition(s));
        EXPECT_LT((loaded.landmarkCovariance(t) - saved.landmarkCovariance(s)).norm(), 1e-12);
        break;
      case LandmarkKind::kLine:
        EXPECT_EQ(loaded.lineLandmark(t).vector(), saved.lineLandmark(s).vector());
        EXPECT_LT((loaded.landmarkCovariance(t) - saved.landmarkCovariance(s)).norm(), 1e-12);
        break;
      case LandmarkKind::kLineAngle:
        EXPECT_EQ(loaded.lineAngle(t), saved.lineAngle(s));
        EXPECT_NEAR(loaded.lineAngleVariance(t), saved.lineAngleVariance(s), 1e-12);
        break;
    }
  }
  // The correlations are not in the file: the loaded landmarks are priors.
  EXPECT_EQ(loaded.covariance().bottomLeftCorner(loaded.stateDim() - 3, 3).norm(), 0.0);

  ASSERT_EQ(support.size(), 2u);
  EXPECT_EQ(support.at(m.line_id).s_min, -2.5);
  EXPECT_EQ(support.at(m.line_id).s_max, 4.25);
  EXPECT_EQ(support.at(m.angle_id).endpoint_ids[0], m.corner_ids[0]);
  EXPECT_EQ(support.at(m.angle_id).endpoint_ids[1], m.corner_ids[1]);

  // And saving the loaded map gives the same file.
  EXPECT_EQ(formatLandmarkMap(toLandmarkMapFile(loaded, support, "map")), formatLandmarkMap(file));
}

// A θ-only line whose endpoint was merged or pruned since it was recorded
// is saved without it; a line without support is saved without an extent.
TEST(MapFileConversion, EveryWrittenMapLoadsAgain) {
  MixedFilter m = mixedFilter();
  std::unordered_map<int, LineSupport> support = supportOf(m);
  support.erase(m.line_id);
  ASSERT_TRUE(m.filter.removeLandmark(m.corner_ids[1]));
  const LandmarkMapFile file = toLandmarkMapFile(m.filter, support, "map");
  ASSERT_EQ(file.lines.size(), 1u);
  EXPECT_FALSE(file.lines[0].has_extent);
  ASSERT_EQ(file.line_angles.size(), 1u);
  EXPECT_EQ(file.line_angles[0].endpoint_ids[0], m.corner_ids[0]);
  EXPECT_EQ(file.line_angles[0].endpoint_ids[1], -1);
  LandmarkMapFile read;
  EXPECT_EQ(parseLandmarkMap(formatLandmarkMap(file), "saved", &read), "");

  // An endpoint id naming a line, not a point, is dropped the same way.
  support[m.angle_id].endpoint_ids[1] = m.line_id;
  EXPECT_EQ(toLandmarkMapFile(m.filter, support, "map").line_angles[0].endpoint_ids[1], -1);
}

TEST(MapFileConversion, RefusedLandmarksAreCountedAndTheirEndpointsDropped) {
  LandmarkMapFile file;
  LandmarkRecord point;
  point.id = 3;
  point.position = Vector2(1.0, 2.0);
  point.covariance = Matrix2::Identity() * 1e-3;
  file.landmarks.push_back(point);
  LineLandmarkRecord line;
  line.id = 5;
  line.p = 2.0;
  line.covariance = Matrix2::Identity() * 1e-3;
  file.lines.push_back(line);
  LineAngleRecord angle;
  angle.id = 8;
  angle.theta = 0.5;
  angle.variance = 1e-4;
  angle.endpoint_ids[0] = 3;
  file.line_angles.push_back(angle);

  // Id 3 is already a line in the filter: the point is refused, and the
  // θ-only line loses its endpoint (3 names no point there).
  EkfSlam filter{FilterOptions{}};
  ASSERT_EQ(filter.addLineLandmark(3, PolarLine{1.0, 0.0}, Matrix2::Identity() * 1e-3),
            FilterStatus::kOk);
  std::unordered_map<int, LineSupport> support;
  EXPECT_EQ(seedFilter(file, &filter, &support), 1);
  EXPECT_EQ(filter.landmarkCount(), 3);
  EXPECT_EQ(filter.landmarkKind(filter.slotOf(3)), LandmarkKind::kLine);
  EXPECT_EQ(support.at(8).endpoint_ids[0], -1);
  EXPECT_EQ(support.count(5), 0u);  // no extent in the file: none known

  // Loading the same map again refuses every landmark and changes nothing.
  const int dim = filter.stateDim();
  EXPECT_EQ(seedFilter(file, &filter), 3);
  EXPECT_EQ(filter.stateDim(), dim);
}

}  // namespace
}  // namespace ekf_slam
