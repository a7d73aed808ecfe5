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

// Two landmarks of each kind, with numbers whose shortest decimal form
// (what PyYAML writes) is shorter than the writer's 17 digits.
LandmarkMapFile smallMixedMap() {
  LandmarkMapFile map;
  auto covariance = [](double a, double ab, double b) {
    Matrix2 c;
    c << a, ab, ab, b;
    return c;
  };
  map.landmarks = {{3, Vector2(1.25, -0.5), covariance(0.01, 0.001, 0.02), 7},
                   {4, Vector2(6.0, 4.1), covariance(0.0004, 0.0, 0.0004), 1}};
  LineLandmarkRecord line;
  line.id = 5;
  line.p = 2.5;
  line.theta = kPi / 2.0;
  line.covariance = covariance(0.0004, 1e-05, 0.0001);
  line.observations = 12;
  line.has_extent = true;
  line.s_min = -1.5;
  line.s_max = 3.0;
  map.lines.push_back(line);
  line = LineLandmarkRecord();
  line.id = 6;
  line.p = 0.75;
  line.theta = -3.0;
  line.covariance = covariance(0.01, -0.0002, 0.002);
  map.lines.push_back(line);
  LineAngleRecord direction;
  direction.id = 8;
  direction.theta = 0.0;
  direction.variance = 0.0001;
  direction.observations = 9;
  direction.endpoint_ids[0] = 3;
  direction.endpoint_ids[1] = 4;
  map.line_angles.push_back(direction);
  direction.id = 9;
  direction.theta = -1.2;
  direction.variance = 2.5e-05;
  direction.observations = 1;
  direction.endpoint_ids[0] = 4;
  direction.endpoint_ids[1] = -1;
  map.line_angles.push_back(direction);
  return map;
}

// What the writer gives for smallMixedMap(), byte for byte: files saved
// before the reader moved to yaml-cpp and after it are the same.
const char kSmallMixedMapText[] =
    "# EKF-SLAM landmarks in the frame below. Points: x, y in m, covariance = the\n"
    "# full 2x2 marginal [xx, xy, yx, yy] in m^2. Lines: x cos(theta) + y sin(theta)\n"
    "# = p (m, rad), covariance of (p, theta), extent = the seen stretch [s_min,\n"
    "# s_max] in m along (-sin(theta), cos(theta)) from the foot point. Line angles:\n"
    "# theta alone (variance in rad^2), offset from the endpoint points (-1: none).\n"
    "# observations = sightings (1: tentative).\n"
    "version: 2\n"
    "frame: map\n"
    "count: 6\n"
    "landmarks:\n"
    "  - {id: 3, x: 1.25, y: -0.5, covariance: [0.01, 0.001, 0.001, 0.02], observations: 7}\n"
    "  - {id: 4, x: 6, y: 4.0999999999999996, covariance: [0.00040000000000000002, 0, 0, "
    "0.00040000000000000002], observations: 1}\n"
    "lines:\n"
    "  - {id: 5, p: 2.5, theta: 1.5707963267948966, covariance: [0.00040000000000000002, "
    "1.0000000000000001e-05, 1.0000000000000001e-05, 0.0001], observations: 12, extent: [-1.5, "
    "3]}\n"
    "  - {id: 6, p: 0.75, theta: -3, covariance: [0.01, -0.00020000000000000001, "
    "-0.00020000000000000001, 0.002], observations: 2}\n"
    "line_angles:\n"
    "  - {id: 8, theta: 0, variance: 0.0001, observations: 9, endpoints: [3, 4]}\n"
    "  - {id: 9, theta: -1.2, variance: 2.5000000000000001e-05, observations: 1, endpoints: [4, "
    "-1]}\n";

TEST(LandmarkMapFile, TheWrittenTextIsUnchanged) {
  EXPECT_EQ(formatLandmarkMap(smallMixedMap()), kSmallMixedMapText);
}

// kSmallMixedMapText loaded and dumped again by PyYAML:
//   d = yaml.safe_load(text)
//   yaml.safe_dump(d, default_flow_style=False)  # kPyYamlBlockText
//   yaml.safe_dump(d, default_flow_style=True)   # kPyYamlFlowText
// (python3-yaml 6.0): keys sorted, comments gone, numbers in their shortest
// form, block lists without indentation, flow mappings wrapped at 80 columns.
const char kPyYamlBlockText[] =
    "count: 6\nframe: map\nlandmarks:\n"
    "- covariance:\n  - 0.01\n  - 0.001\n  - 0.001\n  - 0.02\n"
    "  id: 3\n  observations: 7\n  x: 1.25\n  y: -0.5\n"
    "- covariance:\n  - 0.0004\n  - 0\n  - 0\n  - 0.0004\n"
    "  id: 4\n  observations: 1\n  x: 6\n  y: 4.1\n"
    "line_angles:\n"
    "- endpoints:\n  - 3\n  - 4\n  id: 8\n  observations: 9\n  theta: 0\n  variance: 0.0001\n"
    "- endpoints:\n  - 4\n  - -1\n  id: 9\n  observations: 1\n  theta: -1.2\n  variance: 2.5e-05\n"
    "lines:\n"
    "- covariance:\n  - 0.0004\n  - 1.0e-05\n  - 1.0e-05\n  - 0.0001\n"
    "  extent:\n  - -1.5\n  - 3\n  id: 5\n  observations: 12\n  p: 2.5\n"
    "  theta: 1.5707963267948966\n"
    "- covariance:\n  - 0.01\n  - -0.0002\n  - -0.0002\n  - 0.002\n"
    "  id: 6\n  observations: 2\n  p: 0.75\n  theta: -3\n"
    "version: 2\n";
const char kPyYamlFlowText[] =
    "{count: 6, frame: map, landmarks: [{covariance: [0.01, 0.001, 0.001, 0.02], id: 3,\n"
    "      observations: 7, x: 1.25, y: -0.5}, {covariance: [0.0004, 0, 0, 0.0004], id: 4,\n"
    "      observations: 1, x: 6, y: 4.1}], line_angles: [{endpoints: [3, 4], id: 8, "
    "observations: 9,\n"
    "      theta: 0, variance: 0.0001}, {endpoints: [4, -1], id: 9, observations: 1, theta: "
    "-1.2,\n"
    "      variance: 2.5e-05}], lines: [{covariance: [0.0004, 1.0e-05, 1.0e-05, 0.0001],\n"
    "      extent: [-1.5, 3], id: 5, observations: 12, p: 2.5, theta: 1.5707963267948966},\n"
    "    {covariance: [0.01, -0.0002, -0.0002, 0.002], id: 6, observations: 2, p: 0.75,\n"
    "      theta: -3}], version: 2}\n";

TEST(LandmarkMapFile, PyYamlsBlockAndFlowDumpsLoadAsTheSameMap) {
  const LandmarkMapFile original = smallMixedMap();
  for (const char* text : {kPyYamlBlockText, kPyYamlFlowText}) {
    LandmarkMapFile read;
    ASSERT_EQ(parseLandmarkMap(text, "pyyaml.yaml", &read), "") << text;
    expectSameMaps(read, original);
  }
}

// Whatever the YAML spelling: keys quoted and in another order, comments
// after values, numbers quoted (PyYAML quotes a string such as '1e-4' that
// it did not read as a number), block and flow mixed, `landmarks:` with
// nothing after it, an explicit document start.
TEST(LandmarkMapFile, AnyYamlOfTheSameContentLoads) {
  const std::string text =
      "--- # a map edited by hand\n"
      "\"frame\": 'map'\n"
      "count: 3  # one of each\n"
      "version: 2\n"
      "lines: [{'theta': 1.5707963267948966, p: 2.5, id: 5,\n"
      "         covariance: [0.0004, 1.0e-05, 1.0e-05, 0.0001], extent: [-1.5, 3]}]\n"
      "landmarks:\n"
      "  -   # a point\n"
      "    id: 3\n"
      "    x: '1.25'\n"
      "    y: -0.5\n"
      "    covariance: [0.01, 0.001,\n"
      "                 0.02]\n"
      "line_angles:\n"
      "- {id: 8, theta: 0.0, variance: '1e-4', endpoints: [3, -1], observations: 9}\n";
  LandmarkMapFile map;
  ASSERT_EQ(parseLandmarkMap(text, "edited.yaml", &map), "");
  EXPECT_EQ(map.frame, "map");
  ASSERT_EQ(map.landmarks.size(), 1u);
  EXPECT_EQ(map.landmarks[0].position, Vector2(1.25, -0.5));
  EXPECT_EQ(map.landmarks[0].covariance(1, 0), 0.001);
  EXPECT_EQ(map.landmarks[0].covariance(1, 1), 0.02);
  ASSERT_EQ(map.lines.size(), 1u);
  EXPECT_EQ(map.lines[0].theta, kPi / 2.0);
  EXPECT_TRUE(map.lines[0].has_extent);
  EXPECT_EQ(map.lines[0].s_max, 3.0);
  ASSERT_EQ(map.line_angles.size(), 1u);
  EXPECT_EQ(map.line_angles[0].variance, 1e-4);
  EXPECT_EQ(map.line_angles[0].endpoint_ids[0], 3);
  EXPECT_EQ(map.line_angles[0].observations, 9);
}

std::string fileContents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// The same with PyYAML itself on random maps (17-digit numbers, every kind,
// lines with and without extent), when python3-yaml is installed.
TEST(LandmarkMapFile, PyYamlsDumpsOfRandomMapsLoadBitForBit) {
  if (std::system("/usr/bin/python3 -c 'import yaml' > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "python3-yaml is not installed";
  }
  char dir[] = "/tmp/landmark_map_pyyamlXXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string written = std::string(dir) + "/written.yaml";
  const LandmarkMapFile original = randomMixedMap(20, 11);
  ASSERT_EQ(writeLandmarkMap(written, original), "");
  for (const char* flow : {"False", "True"}) {
    const std::string dumped = std::string(dir) + "/dumped.yaml";
    const std::string command =
        std::string("/usr/bin/python3 -c 'import sys, yaml; ") +
        "open(sys.argv[2], \"w\").write(yaml.safe_dump(yaml.safe_load(open(sys.argv[1])), " +
        "default_flow_style=" + flow + "))' " + written + " " + dumped;
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    LandmarkMapFile read;
    ASSERT_EQ(readLandmarkMap(dumped, &read), "") << fileContents(dumped);
    expectSameMaps(read, original);
    std::remove(dumped.c_str());
  }
  std::remove(written.c_str());
  ::rmdir(dir);
}

// A frame is written so that it reads back as itself: plain when YAML
// reads it so, else double-quoted.
TEST(LandmarkMapFile, AnyFrameReadsBackAsWritten) {
  for (const std::string frame :
       {"map", "robot_1/map", "odom # 2", "a: b", "[map]", "null", "~", "'quoted'", "\"double\"",
        " padded ", "tab\there", "line\nbreak", "back\\slash", "-", "cart\xc3\xa9sien"}) {
    LandmarkMapFile map = smallMixedMap();
    map.frame = frame;
    const std::string text = formatLandmarkMap(map);
    LandmarkMapFile read;
    ASSERT_EQ(parseLandmarkMap(text, "frame.yaml", &read), "") << text;
    EXPECT_EQ(read.frame, frame) << text;
  }
  LandmarkMapFile map;
  map.frame = "robot_1/map";
  EXPECT_NE(formatLandmarkMap(map).find("\nframe: robot_1/map\n"), std::string::npos);
  map.frame = "odom # 2";
  EXPECT_NE(formatLandmarkMap(map).find("\nframe: \"odom # 2\"\n"), std::string::npos);
}

// Text that is not YAML, or not this file's YAML, is refused with the line
// of the value at fault; nothing escapes as an exception.
TEST(LandmarkMapFile, YamlErrorsNameTheLineAndLeaveTheMapAlone) {
  const std::string head = "version: 2\ncount: 1\nlines: []\nline_angles: []\n";
  struct Case {
    std::string text;
    std::string expected;
  };
  const Case cases[] = {
      {head + "landmarks:\n  - {id: 1, x: 0, y: 0, covariance: [1, 0, 0, 1]\n",
       "bad.yaml:6: not valid YAML"},
      {head + "landmarks: [\n", "bad.yaml:5: not valid YAML"},
      {"landmarks: []\n\tcount: 0\n", "bad.yaml:2: not valid YAML"},
      {head + "landmarks:\n- id: 1\n  x: nan\n  y: 0\n  covariance: [1, 0, 0, 1]\n",
       "bad.yaml:7: x must be a finite number, got 'nan'"},
      {head + "landmarks:\n- id: 1\n  x: 0\n  y: 0\n  covariance:\n  - 1\n  - 0\n  - 0\n  - -1\n",
       "bad.yaml:10: covariance is not positive definite"},
      {head + "landmarks:\n- id: 1\n  x: 0\n  y: 0\n  covariance:\n  - 1\n  - .inf\n",
       "bad.yaml:11: covariance entries must be finite numbers, got '.inf'"},
      {head + "landmarks:\n- id: 1\n  x: 0\n  x: 0\n  y: 0\n  covariance: [1, 0, 0, 1]\n",
       "bad.yaml:8: key 'x' given twice"},
      {head + "landmarks:\n- id: [1]\n  x: 0\n  y: 0\n  covariance: [1, 0, 0, 1]\n",
       "bad.yaml:6: id must be a non-negative integer, got [1]"},
      {head + "landmarks:\n- [1, 0, 0]\n", "bad.yaml:6: expected an entry {id: .., ...}"},
      {head + "landmarks: {id: 1}\n", "bad.yaml:5: 'landmarks:' must be followed by a list"},
      {head + "landmarks: []\ncount: 0\n", "bad.yaml:6: 'count:' given twice"},
      {"frame: [map]\n" + head + "landmarks: []\n", "bad.yaml:1: frame must be a frame id"},
      {"- version: 2\n", "bad.yaml:1: expected keys (version, frame"},
      {"just text\n", "bad.yaml:1: expected keys (version, frame"},
      {"? [a, b]\n: c\nlandmarks: []\n", "bad.yaml:1: expected a key, got [a, b]"},
      {head + "landmarks: []\n---\nlandmarks: []\n", "bad.yaml:6: more than one YAML document"},
      // yaml-cpp's LoadAll loops for ever on these (a stray ',' after a document).
      {"{version: 2, count: 0, landmarks: [], lines: [], line_angles: []}\n,\n",
       "bad.yaml:2: more than one YAML document"},
      {"{[]},{[][{[]}]}", "bad.yaml:1: more than one YAML document"},
      {"version: 3\ncount: 0\nlandmarks: []\n", "bad.yaml:1: format version 3 is newer"},
      {"version: 2\ncount: 7\nlandmarks: []\nlines: []\nline_angles: []\n",
       "bad.yaml: 0 landmarks where 'count' says 7"},
      {"", "bad.yaml: no 'landmarks:' list"},
      {"# only a comment\n", "bad.yaml: no 'landmarks:' list"},
  };
  for (const Case& c : cases) {
    LandmarkMapFile map = randomMixedMap(2, 1);
    const std::string error = parseLandmarkMap(c.text, "bad.yaml", &map);
    EXPECT_EQ(error.find(c.expected), 0u) << c.text << " → " << error;
    EXPECT_EQ(map.size(), 6u);  // untouched
  }
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
