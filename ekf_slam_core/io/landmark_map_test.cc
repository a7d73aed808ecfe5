// Landmark map files: exact round trip of every landmark kind, the older
// offline runner's 3-value form and version 1 files, errors that name the
// line, and seeding a filter from a saved map.
#include "ekf_slam_core/io/landmark_map.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>
#include <Eigen/Eigenvalues>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "ekf_slam_core/filter/ekf_slam.h"

namespace ekf_slam {
namespace {

LandmarkMapFile randomMap(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coordinate(-50.0, 50.0), scale(1e-6, 0.5);
  LandmarkMapFile map;
  for (int i = 0; i < count; ++i) {
    LandmarkRecord r;
    r.id = 3 * i + 1;  // gaps, as after pruning
    r.position = Vector2(coordinate(rng), coordinate(rng));
    Eigen::Matrix2d a;
    a << scale(rng), scale(rng), scale(rng), scale(rng);
    r.covariance = a * a.transpose() + 1e-9 * Matrix2::Identity();  // SPD
    r.observations = 1 + i % 5;
    map.landmarks.push_back(r);
  }
  return map;
}

// randomMap's points plus `count` lines of each kind, ids after theirs; the
// θ-only lines end on the points.
LandmarkMapFile randomMixedMap(int count, unsigned seed) {
  LandmarkMapFile map = randomMap(count, seed);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<double> offset(0.0, 50.0), angle(-kPi, kPi), scale(1e-6, 0.1);
  for (int i = 0; i < count; ++i) {
    LineLandmarkRecord line;
    line.id = 3 * count + 2 * i;
    line.p = offset(rng);
    line.theta = angle(rng);
    Eigen::Matrix2d a;
    a << scale(rng), scale(rng), scale(rng), scale(rng);
    line.covariance = a * a.transpose() + 1e-9 * Matrix2::Identity();
    line.observations = 2 + i;
    line.has_extent = i % 2 == 0;  // also lines whose extent is unknown
    line.s_min = -offset(rng);
    line.s_max = offset(rng);
    map.lines.push_back(line);
    LineAngleRecord direction;
    direction.id = line.id + 1;
    direction.theta = angle(rng);
    direction.variance = scale(rng) * scale(rng) + 1e-12;
    direction.observations = 1 + i;
    direction.endpoint_ids[0] = map.landmarks[i].id;
    direction.endpoint_ids[1] = i % 2 ? map.landmarks[(i + 1) % count].id : -1;
    map.line_angles.push_back(direction);
  }
  return map;
}

void expectSameMaps(const LandmarkMapFile& read, const LandmarkMapFile& original) {
  EXPECT_EQ(read.frame, original.frame);
  ASSERT_EQ(read.landmarks.size(), original.landmarks.size());
  for (size_t i = 0; i < read.landmarks.size(); ++i) {
    EXPECT_EQ(read.landmarks[i].id, original.landmarks[i].id);
    EXPECT_EQ(read.landmarks[i].position, original.landmarks[i].position);  // bit-exact
    EXPECT_EQ(read.landmarks[i].covariance, original.landmarks[i].covariance);
    EXPECT_EQ(read.landmarks[i].observations, original.landmarks[i].observations);
  }
  ASSERT_EQ(read.lines.size(), original.lines.size());
  for (size_t i = 0; i < read.lines.size(); ++i) {
    const LineLandmarkRecord &a = read.lines[i], &b = original.lines[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.p, b.p);
    EXPECT_EQ(a.theta, b.theta);
    EXPECT_EQ(a.covariance, b.covariance);
    EXPECT_EQ(a.observations, b.observations);
    EXPECT_EQ(a.has_extent, b.has_extent);
    if (b.has_extent) {
      EXPECT_EQ(a.s_min, b.s_min);
      EXPECT_EQ(a.s_max, b.s_max);
    }
  }
  ASSERT_EQ(read.line_angles.size(), original.line_angles.size());
  for (size_t i = 0; i < read.line_angles.size(); ++i) {
    const LineAngleRecord &a = read.line_angles[i], &b = original.line_angles[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.theta, b.theta);
    EXPECT_EQ(a.variance, b.variance);
    EXPECT_EQ(a.observations, b.observations);
    EXPECT_EQ(a.endpoint_ids[0], b.endpoint_ids[0]);
    EXPECT_EQ(a.endpoint_ids[1], b.endpoint_ids[1]);
  }
}

TEST(LandmarkMapFile, RoundTripThroughAFileIsExact) {
  const LandmarkMapFile original = randomMixedMap(40, 7);
  char path[] = "/tmp/landmark_map_testXXXXXX";
  const int fd = ::mkstemp(path);
  ASSERT_GE(fd, 0);
  ::close(fd);
  ASSERT_EQ(writeLandmarkMap(path, original), "");
  LandmarkMapFile read;
  ASSERT_EQ(readLandmarkMap(path, &read), "");
  std::remove(path);
  expectSameMaps(read, original);
}

TEST(LandmarkMapFile, EmptyMapRoundTrips) {
  LandmarkMapFile empty, read;
  empty.frame = "world";
  read.landmarks.resize(3);
  ASSERT_EQ(parseLandmarkMap(formatLandmarkMap(empty), "text", &read), "");
  EXPECT_EQ(read.frame, "world");
  EXPECT_TRUE(read.landmarks.empty());
  EXPECT_EQ(read.size(), 0u);
}

// What version 1 wrote (points only) is read as before.
TEST(LandmarkMapFile, ReadsVersionOneFiles) {
  const std::string text =
      "version: 1\nframe: map\ncount: 2\nlandmarks:\n"
      "  - {id: 3, x: 1.25, y: -0.5, covariance: [0.01, 0.001, 0.001, 0.02], observations: 7}\n"
      "  - {id: 9, x: -4, y: 25, covariance: [0.04, 0, 0.04]}\n";
  LandmarkMapFile map;
  ASSERT_EQ(parseLandmarkMap(text, "v1.yaml", &map), "");
  ASSERT_EQ(map.landmarks.size(), 2u);
  EXPECT_EQ(map.landmarks[0].observations, 7);
  EXPECT_DOUBLE_EQ(map.landmarks[1].covariance(1, 1), 0.04);
  EXPECT_TRUE(map.lines.empty() && map.line_angles.empty());
  // Lines were not part of version 1.
  EXPECT_NE(parseLandmarkMap(text + "lines: []\n", "v1.yaml", &map).find("need 'version: 2'"),
            std::string::npos);
}

TEST(LandmarkMapFile, ReadsTheOfflineRunnersThreeValueCovariance) {
  const std::string text =
      "# EKF-SLAM point landmarks\n"
      "landmarks:\n"
      "  - {id: 4, x: 1.5, y: -2, covariance: [0.04, 0.01, 0.09], observations: 6}\n"
      "  - {id: 9, x: 0, y: 3.25, covariance: [0.01, 0, 0.01]}\n";
  LandmarkMapFile map;
  ASSERT_EQ(parseLandmarkMap(text, "offline.yaml", &map), "");
  ASSERT_EQ(map.landmarks.size(), 2u);
  EXPECT_EQ(map.landmarks[0].id, 4);
  EXPECT_DOUBLE_EQ(map.landmarks[0].position.y(), -2.0);
  EXPECT_DOUBLE_EQ(map.landmarks[0].covariance(1, 0), 0.01);
  EXPECT_DOUBLE_EQ(map.landmarks[0].covariance(1, 1), 0.09);
  EXPECT_EQ(map.landmarks[0].observations, 6);
  EXPECT_EQ(map.landmarks[1].observations, 2);  // absent: not tentative
}

TEST(LandmarkMapFile, ErrorsNameTheLineAndTheProblemAndLeaveTheMapAlone) {
  const std::string head = "landmarks:\n";
  struct Case {
    std::string entry;
    std::string expected;
  };
  const Case cases[] = {
      {"  - {id: 1, x: 0, y: 0, covariance: [1, 0, 0, -1]}\n", "not positive definite"},
      {"  - {id: 1, x: 0, y: 0, covariance: [1, 0.5, 0, 1]}\n", "not symmetric"},
      {"  - {id: 1, x: nan, y: 0, covariance: [1, 0, 0, 1]}\n", "x must be a finite number"},
      {"  - {id: -2, x: 0, y: 0, covariance: [1, 0, 0, 1]}\n", "id must be"},
      {"  - {id: 1, x: 0, covariance: [1, 0, 0, 1]}\n", "missing key 'y'"},
      {"  - {id: 1, x: 0, y: 0, z: 1, covariance: [1, 0, 0, 1]}\n", "unknown key 'z'"},
      {"  - {id: 1, x: 0, y: 0, covariance: [1, 0]}\n", "covariance needs 4 values"},
      {"  - {id: 1, x: 0, y: 0, covariance: [1, 0, 0, 1]}\n"
       "  - {id: 1, x: 2, y: 0, covariance: [1, 0, 0, 1]}\n",
       "id 1 appears twice"},
  };
  for (const Case& c : cases) {
    LandmarkMapFile map = randomMap(2, 1);
    const std::string error = parseLandmarkMap(head + c.entry, "bad.yaml", &map);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.entry << " → " << error;
    EXPECT_EQ(error.rfind("bad.yaml:", 0), 0u) << error;
    EXPECT_EQ(map.landmarks.size(), 2u);  // untouched
  }
  LandmarkMapFile map;
  EXPECT_NE(parseLandmarkMap("frame: map\n", "f", &map).find("no 'landmarks:' list"),
            std::string::npos);
  EXPECT_NE(parseLandmarkMap("landmarks:\ncolour: red\n", "f", &map).find("f:2: unknown key"),
            std::string::npos);
  EXPECT_NE(readLandmarkMap("/nonexistent/dir/map.yaml", &map).find("cannot open"),
            std::string::npos);
}

// Every check made on points holds for the line kinds too.
TEST(LandmarkMapFile, LineErrorsNameTheLineAndTheProblemAndLeaveTheMapAlone) {
  const std::string head =
      "version: 2\ncount: 2\n"
      "landmarks:\n  - {id: 1, x: 0, y: 0, covariance: [1, 0, 0, 1]}\n";
  const std::string no_angles = "line_angles: []\n", no_lines = "lines: []\n";
  auto line = [&](const std::string& entry) { return "lines:\n  - " + entry + "\n" + no_angles; };
  auto angle = [&](const std::string& entry) {
    return no_lines + "line_angles:\n  - " + entry + "\n";
  };
  struct Case {
    std::string body;
    std::string expected;
  };
  const Case cases[] = {
      {line("{id: 2, p: 1, theta: 0, covariance: [1, 0, 0, -1]}"), "not positive definite"},
      {line("{id: 2, p: 1, theta: 0, covariance: [1, 0.5, 0, 1]}"), "not symmetric"},
      {line("{id: 2, p: inf, theta: 0, covariance: [1, 0, 0, 1]}"), "p must be a finite number"},
      {line("{id: 2, p: 1, theta: nan, covariance: [1, 0, 0, 1]}"), "theta must be a finite"},
      {line("{id: 2, p: -1, theta: 0, covariance: [1, 0, 0, 1]}"), "p must be >= 0"},
      {line("{id: 2, p: 1, theta: 3.5, covariance: [1, 0, 0, 1]}"), "theta must lie in"},
      {line("{id: 2, p: 2e6, theta: 0, covariance: [1, 0, 0, 1]}"), "p beyond"},
      {line("{id: 2, p: 1, theta: 0, covariance: [1e7, 0, 0, 1]}"), "covariance beyond"},
      {line("{id: 2, p: 1, theta: 0, covariance: [1, 0, 0, 10]}"), "covariance beyond"},
      {line("{id: 2, p: 1, theta: 0, covariance: [1, 0, 0, 1], extent: [2, 1]}"), "s_min > s_max"},
      {line("{id: 2, p: 1, theta: 0, covariance: [1, 0, 0, 1], extent: [1]}"), "extent needs 2"},
      {line("{id: 2, p: 1, theta: 0, covariance: [1, 0, 0, 1], extent: [0, inf]}"), "finite"},
      {line("{id: 2, p: 1, theta: 0, covariance: [1, 0, 0, 1], extent: [0, 3e6]}"),
       "extent beyond"},
      {line("{id: 2, p: 1, covariance: [1, 0, 0, 1]}"), "missing key 'theta'"},
      {line("{id: 2, p: 1, theta: 0, x: 1, covariance: [1, 0, 0, 1]}"), "unknown key 'x'"},
      {line("{id: 1, p: 1, theta: 0, covariance: [1, 0, 0, 1]}"), "id 1 appears twice"},
      {angle("{id: 2, theta: 0, variance: 0}"), "variance must be positive"},
      {angle("{id: 2, theta: 0, variance: -1e-4}"), "variance must be positive"},
      {angle("{id: 2, theta: 0, variance: nan}"), "variance must be a finite"},
      {angle("{id: 2, theta: 0, variance: 10}"), "variance beyond"},
      {angle("{id: 2, theta: -4, variance: 1e-4}"), "theta must lie in"},
      {angle("{id: 2, theta: 0, variance: 1e-4, endpoints: [1]}"), "endpoints must be two"},
      {angle("{id: 2, theta: 0, variance: 1e-4, endpoints: [1, -2]}"), "endpoints must be two"},
      {angle("{id: 2, theta: 0, variance: 1e-4, endpoints: [1, 1]}"), "point 1 twice"},
      {angle("{id: 2, theta: 0, variance: 1e-4, endpoints: [1, 7]}"),
       "endpoint 7 is not a point landmark"},
      {angle("{id: 1, theta: 0, variance: 1e-4}"), "id 1 appears twice"},
      {"lines:\n  - {id: 2, p: 1, theta: 0, covariance: [1, 0, 0, 1]}\n", "no 'line_angles:'"},
      {no_lines + no_lines + no_angles, "'lines:' given twice"},
  };
  for (const Case& c : cases) {
    LandmarkMapFile map = randomMixedMap(2, 1);
    const std::string error = parseLandmarkMap(head + c.body, "bad.yaml", &map);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.body << " → " << error;
    EXPECT_EQ(error.rfind("bad.yaml:", 0), 0u) << error;
    EXPECT_EQ(map.size(), 6u);  // untouched
  }
  // The endpoint error names the line of the θ-only entry; a line is no endpoint.
  LandmarkMapFile map;
  EXPECT_NE(
      parseLandmarkMap("version: 2\ncount: 2\nlandmarks: []\n"
                       "lines:\n  - {id: 2, p: 1, theta: 0, covariance: [1, 0, 0, 1]}\n"
                       "line_angles:\n  - {id: 3, theta: 0, variance: 1, endpoints: [2, -1]}\n",
                       "f", &map)
          .find("f:7: endpoint 2 is not a point landmark"),
      std::string::npos);
  EXPECT_NE(parseLandmarkMap(head + angle("{id: 2, theta: 0, variance: 1e-4, endpoints: [5, -1]}"),
                             "f", &map)
                .find("f:7: endpoint 5"),
            std::string::npos);
  // And a valid one loads, the endpoints as given.
  ASSERT_EQ(
      parseLandmarkMap(head + angle("{id: 2, theta: 3.14, variance: 1e-4, endpoints: [-1, 1]}"),
                       "good.yaml", &map),
      "");
  ASSERT_EQ(map.line_angles.size(), 1u);
  EXPECT_EQ(map.line_angles[0].endpoint_ids[0], -1);
  EXPECT_EQ(map.line_angles[0].endpoint_ids[1], 1);
  EXPECT_EQ(map.line_angles[0].observations, 2);
}

std::string fileContents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// A file cut at any line boundary inside the lists is refused: the count in
// the header says how many landmarks must follow, and version 2 names every
// list, so that even a cut just before an empty list is seen.
TEST(LandmarkMapFile, AFileCutShortIsRefused) {
  const std::string text = formatLandmarkMap(randomMixedMap(4, 3));
  LandmarkMapFile map;
  ASSERT_EQ(parseLandmarkMap(text, "whole.yaml", &map), "");
  size_t cut = text.find("\nlandmarks:");
  int refused = 0;
  while ((cut = text.find('\n', cut + 1)) != std::string::npos && cut + 1 < text.size()) {
    LandmarkMapFile partial = randomMap(2, 9);
    const std::string error = parseLandmarkMap(text.substr(0, cut + 1), "cut.yaml", &partial);
    EXPECT_NE(error.find("cut short"), std::string::npos) << error;
    EXPECT_EQ(partial.landmarks.size(), 2u);  // untouched
    ++refused;
  }
  // Every cut from just after 'landmarks:' to just before the last entry:
  // 'landmarks:', 4 points, 'lines:', 4 lines, 'line_angles:', 3 of its 4.
  EXPECT_EQ(refused, 1 + 4 + 1 + 4 + 1 + 3);

  const std::string points_only = formatLandmarkMap(randomMap(3, 3));
  const size_t before_lines = points_only.find("lines: []");
  ASSERT_NE(before_lines, std::string::npos);
  EXPECT_NE(
      parseLandmarkMap(points_only.substr(0, before_lines), "cut.yaml", &map).find("cut short"),
      std::string::npos);
}

TEST(LandmarkMapFile, VersionsAndAbsurdValues) {
  LandmarkMapFile map;
  // A file from before the version key: read as before.
  EXPECT_EQ(parseLandmarkMap("frame: map\nlandmarks:\n"
                             "  - {id: 1, x: 0, y: 0, covariance: [1, 0, 0, 1]}\n",
                             "old.yaml", &map),
            "");
  EXPECT_NE(parseLandmarkMap("version: 3\ncount: 0\nlandmarks: []\n", "new.yaml", &map)
                .find("newer than this program reads"),
            std::string::npos);
  EXPECT_NE(parseLandmarkMap("version: 1\nlandmarks: []\n", "v1.yaml", &map).find("no 'count:'"),
            std::string::npos);
  const std::string head = "version: 1\ncount: 1\nlandmarks:\n";
  EXPECT_NE(parseLandmarkMap(head + "  - {id: 1, x: 0, y: 0, covariance: [1e300, 0, 0, 1]}\n",
                             "huge.yaml", &map)
                .find("covariance beyond"),
            std::string::npos);
  EXPECT_NE(parseLandmarkMap(head + "  - {id: 1, x: 1e7, y: 0, covariance: [1, 0, 0, 1]}\n",
                             "far.yaml", &map)
                .find("position beyond"),
            std::string::npos);
  EXPECT_NE(parseLandmarkMap(head + "  - {id: 1, x: 0, y: 0, covariance: [nan, 0, 0, 1]}\n",
                             "nan.yaml", &map)
                .find("finite"),
            std::string::npos);
}

// A save that fails halfway (here the kernel refuses writes beyond a file
// size limit, as a full disk refuses blocks) leaves the earlier map
// byte-identical and no temporary file behind.
TEST(LandmarkMapFile, AFailedSaveLeavesTheEarlierFileUntouched) {
  char dir[] = "/tmp/landmark_map_saveXXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/map.yaml";
  ASSERT_EQ(writeLandmarkMap(path, randomMap(5, 1)), "");
  const std::string before = fileContents(path);
  const std::string bigger = formatLandmarkMap(randomMap(400, 2));
  ASSERT_GT(bigger.size(), 2 * before.size());

  struct FileSizeLimit {  // RLIMIT_FSIZE for this process, restored at scope exit
    rlimit saved{};
    void (*handler)(int) = nullptr;
    explicit FileSizeLimit(rlim_t bytes) {
      ::getrlimit(RLIMIT_FSIZE, &saved);
      handler = std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead
      rlimit limited = saved;
      limited.rlim_cur = bytes;
      ::setrlimit(RLIMIT_FSIZE, &limited);
    }
    ~FileSizeLimit() {
      ::setrlimit(RLIMIT_FSIZE, &saved);
      std::signal(SIGXFSZ, handler);
    }
  };
  std::string error;
  {
    const FileSizeLimit limit(before.size() + 100);
    error = writeLandmarkMap(path, randomMap(400, 2));
  }
  EXPECT_NE(error.find("earlier file is unchanged"), std::string::npos) << error;
  EXPECT_EQ(fileContents(path), before);
  // Nothing else left in the directory.
  EXPECT_EQ(std::system(("test $(ls -A " + std::string(dir) + " | wc -l) -eq 1").c_str()), 0);
  // And without the limit the same save goes through.
  ASSERT_EQ(writeLandmarkMap(path, randomMap(400, 2)), "");
  EXPECT_EQ(fileContents(path), bigger);
  std::remove(path.c_str());
  ::rmdir(dir);
}

TEST(SeedingTheFilter, LoadedLandmarksKeepIdsMeansCovariancesAndAreUncorrelated) {
  FilterOptions options;
  EkfSlam filter(options, Pose2(1.0, 2.0, 0.3), Matrix3::Identity() * 0.01);
  const LandmarkMapFile map = randomMap(5, 3);
  for (const LandmarkRecord& r : map.landmarks) {
    ASSERT_EQ(filter.addLandmark(r.id, r.position, r.covariance, r.observations),
              FilterStatus::kOk);
  }
  ASSERT_EQ(filter.landmarkCount(), 5);
  for (int s = 0; s < 5; ++s) {
    EXPECT_EQ(filter.landmarks()[s].id, map.landmarks[s].id);
    EXPECT_EQ(filter.landmarkPosition(s), map.landmarks[s].position);
    EXPECT_TRUE(filter.landmarkCovariance(s).isApprox(map.landmarks[s].covariance, 1e-15));
    // No correlation with the pose or any other landmark.
    const int row = filter.landmarkIndex(s);
    EXPECT_EQ(filter.covariance().block(row, 0, 2, row).norm(), 0.0);
  }
  EXPECT_TRUE(filter.poseCovariance().isApprox(Matrix3::Identity() * 0.01));

  // Refusals leave the state alone.
  const int dim = filter.stateDim();
  EXPECT_EQ(filter.addLandmark(map.landmarks[0].id, Vector2(0, 0), Matrix2::Identity()),
            FilterStatus::kDuplicateLandmark);
  EXPECT_EQ(filter.addLandmark(100, Vector2(0, 0), -Matrix2::Identity()),
            FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.addLandmark(100, Vector2(NAN, 0), Matrix2::Identity()),
            FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.stateDim(), dim);

  // A landmark found later gets an id above every loaded one.
  PointObservation z;
  z.z = {2.0, 0.1};
  z.covariance = Matrix2::Identity() * 1e-4;
  int id = -1;
  ASSERT_EQ(filter.augment(z, &id), FilterStatus::kOk);
  EXPECT_GT(id, map.landmarks.back().id);
}

// A prior the filter cannot carry through its updates is refused; one at
// the bound stays positive definite, and so savable and loadable, through
// many updates (a 1e300 m² prior once left P indefinite after 20 scans and
// the node saved a map it then refused to load).
TEST(SeedingTheFilter, RefusesAPriorItCannotRepresentAndKeepsOneAtTheBoundDefinite) {
  FilterOptions options;
  EkfSlam filter(options, Pose2(), Matrix3::Identity() * 1e-4);
  EXPECT_EQ(filter.addLandmark(1, Vector2(3, 0), Matrix2::Identity() * 1e300),
            FilterStatus::kUnrepresentablePrior);
  Matrix2 thin;
  thin << 1.0, 0.0, 0.0, 1e-14;
  EXPECT_EQ(filter.addLandmark(1, Vector2(3, 0), thin), FilterStatus::kUnrepresentablePrior);
  EXPECT_EQ(filter.stateDim(), EkfSlam::kPoseDim);
  ASSERT_EQ(
      filter.addLandmark(1, Vector2(3, 0.5), Matrix2::Identity() * EkfSlam::kMaxPriorVariance),
      FilterStatus::kOk);
  ASSERT_EQ(filter.addLandmark(2, Vector2(2, -1), Matrix2::Identity() * 1e-4), FilterStatus::kOk);
  Pose2 odometry;
  for (int k = 0; k < 50; ++k) {
    const Pose2 next = compose(odometry, Pose2(0.02, 0.0, 0.01));
    ASSERT_EQ(filter.predict(odometry, next, 0.2), FilterStatus::kOk);
    odometry = next;
    std::vector<PointObservation> z;
    for (int slot = 0; slot < 2; ++slot) {
      EkfSlam::Prediction p;
      ASSERT_TRUE(filter.predictObservation(slot, &p));
      PointObservation obs;
      obs.z = p.z;
      obs.covariance = Matrix2::Identity() * 1e-4;
      z.push_back(obs);
    }
    ASSERT_EQ(filter.update(z, {{0, 1}, {1, 2}}), FilterStatus::kOk) << "step " << k;
    const Eigen::MatrixXd P = filter.covariance();
    const double lowest =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P, Eigen::EigenvaluesOnly).eigenvalues()(0);
    ASSERT_GT(lowest, -1e-12 * P.diagonal().maxCoeff()) << "step " << k;
    for (int slot = 0; slot < 2; ++slot) {
      const Matrix2 c = filter.landmarkCovariance(slot);
      ASSERT_TRUE(c(0, 0) > 0 && c(1, 1) > 0 && c.determinant() > 0) << "step " << k;
    }
  }
  // And the map it would save loads again.
  LandmarkMapFile saved;
  for (int slot = 0; slot < 2; ++slot) {
    LandmarkRecord r;
    r.id = filter.landmarks()[slot].id;
    r.position = filter.landmarkPosition(slot);
    r.covariance = filter.landmarkCovariance(slot);
    saved.landmarks.push_back(r);
  }
  LandmarkMapFile loaded;
  EXPECT_EQ(parseLandmarkMap(formatLandmarkMap(saved), "saved", &loaded), "");
}

TEST(SeedingTheFilter, LocalisationOnlyRefusesNewLandmarks) {
  EkfSlam filter(FilterOptions{});
  PointObservation z;
  z.z = {2.0, 0.1};
  z.covariance = Matrix2::Identity() * 1e-4;
  filter.setMappingEnabled(false);
  EXPECT_EQ(filter.augment(z), FilterStatus::kMappingDisabled);
  EXPECT_EQ(filter.landmarkCount(), 0);
  filter.setMappingEnabled(true);
  EXPECT_EQ(filter.augment(z), FilterStatus::kOk);
  EXPECT_EQ(filter.landmarkCount(), 1);
}

}  // namespace
}  // namespace ekf_slam
