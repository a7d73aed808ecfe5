#include "ekf_slam_core/io/grid_map_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

namespace ekf_slam {
namespace {

class GridMapFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir[] = "/tmp/grid_map_fileXXXXXX";
    ASSERT_NE(::mkdtemp(dir), nullptr);
    dir_ = dir;
  }
  void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }

  void writeText(const std::string& name, const std::string& text) {
    std::ofstream(dir_ + "/" + name, std::ios::binary) << text;
  }
  std::string readText(const std::string& name) {
    std::ifstream in(dir_ + "/" + name, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

  std::string dir_;
};

GridMapFile randomGrid(int width, int height, unsigned seed) {
  GridMapFile grid;
  grid.resolution = static_cast<double>(0.05f);  // a nav_msgs resolution is a float32
  grid.origin_x = -12.345678901234;
  grid.origin_y = 3.0 / 7.0;
  grid.origin_yaw = 0.0;
  grid.width = width;
  grid.height = height;
  std::mt19937 rng(seed);
  const int8_t values[] = {-1, 0, 100};
  for (int i = 0; i < width * height; ++i) grid.cells.push_back(values[rng() % 3]);
  return grid;
}

TEST_F(GridMapFileTest, ASaveAndALoadGiveTheGridBitForBit) {
  const GridMapFile saved = randomGrid(37, 23, 1);
  const std::string path = dir_ + "/office_grid.yaml";
  ASSERT_EQ(writeGridMap(path, saved), "");
  GridMapFile loaded;
  ASSERT_EQ(readGridMap(path, &loaded), "");
  EXPECT_EQ(loaded.width, saved.width);
  EXPECT_EQ(loaded.height, saved.height);
  EXPECT_EQ(loaded.resolution, saved.resolution);
  EXPECT_EQ(static_cast<float>(loaded.resolution), 0.05f);
  EXPECT_EQ(loaded.origin_x, saved.origin_x);
  EXPECT_EQ(loaded.origin_y, saved.origin_y);
  EXPECT_EQ(loaded.origin_yaw, saved.origin_yaw);
  EXPECT_EQ(loaded.cells, saved.cells);
}

TEST_F(GridMapFileTest, TheFilesAreWhatMapServerReads) {
  GridMapFile grid;
  grid.width = 3;
  grid.height = 2;
  grid.cells = {100, 0,   -1,  // bottom row (y = origin)
                -1,  100, 0};  // top row
  ASSERT_EQ(writeGridMap(dir_ + "/m.yaml", grid), "");
  const std::string yaml = readText("m.yaml");
  EXPECT_NE(yaml.find("image: m.pgm\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("resolution: 0.050000000000000003\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"), std::string::npos);
  const std::string image = readText("m.pgm");
  const std::string header = "P5\n# ekf_slam occupancy grid\n3 2\n255\n";
  ASSERT_EQ(image.substr(0, header.size()), header);
  // The top row first; occupied black (0), free white (254), unknown grey (205).
  const std::string pixels = image.substr(header.size());
  const std::string expected = {static_cast<char>(205), static_cast<char>(0),
                                static_cast<char>(254), static_cast<char>(0),
                                static_cast<char>(254), static_cast<char>(205)};
  EXPECT_EQ(pixels, expected);
}

TEST_F(GridMapFileTest, ReadsMapServerMapsWithTheirOwnThresholds) {
  // A map drawn by hand: grey levels, a comment in the header, negate.
  writeText("drawn.pgm", std::string("P5\n# drawn\n4 1\n255\n") + static_cast<char>(0) +
                             static_cast<char>(100) + static_cast<char>(200) +
                             static_cast<char>(255));
  writeText("drawn.yaml",
            "image: drawn.pgm\nresolution: 0.1\norigin: [1.0, -2.0, 0.5]\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.25\nnegate: 0\nmode: trinary\n");
  GridMapFile grid;
  ASSERT_EQ(readGridMap(dir_ + "/drawn.yaml", &grid), "");
  // occupancy (255 - p) / 255: 1.0, 0.61, 0.22, 0.0
  EXPECT_EQ(grid.cells, (std::vector<int8_t>{100, -1, 0, 0}));
  EXPECT_EQ(grid.origin_yaw, 0.5);
  writeText("drawn.yaml",
            "image: drawn.pgm\nresolution: 0.1\norigin: [1.0, -2.0, 0.5]\nnegate: 1\n");
  ASSERT_EQ(readGridMap(dir_ + "/drawn.yaml", &grid), "");
  // occupancy p / 255 with the default thresholds (0.65, 0.196): 0, 0.39, 0.78, 1
  EXPECT_EQ(grid.cells, (std::vector<int8_t>{0, -1, 100, 100}));
}

// The YAML file writeGridMap gave for randomGrid(.., ..) at g.yaml, loaded
// and dumped again by PyYAML (python3-yaml 6.0):
//   d = yaml.safe_load(text)
//   yaml.safe_dump(d, default_flow_style=False)  # kPyYamlBlockText
//   yaml.safe_dump(d, default_flow_style=True)   # kPyYamlFlowText
// Keys sorted, numbers in their shortest form, `origin` a block list
// (block) or a flow list over two lines (flow).
const char kWrittenText[] =
    "image: g.pgm\nresolution: 0.05000000074505806\n"
    "origin: [-12.345678901234001, 0.42857142857142855, 0]\nnegate: 0\n"
    "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
const char kPyYamlBlockText[] =
    "free_thresh: 0.196\nimage: g.pgm\nnegate: 0\noccupied_thresh: 0.65\norigin:\n"
    "- -12.345678901234\n- 0.42857142857142855\n- 0\nresolution: 0.05000000074505806\n";
const char kPyYamlFlowText[] =
    "{free_thresh: 0.196, image: g.pgm, negate: 0, occupied_thresh: 0.65, origin: "
    "[-12.345678901234,\n"
    "    0.42857142857142855, 0], resolution: 0.05000000074505806}\n";

TEST_F(GridMapFileTest, TheWrittenYamlIsUnchangedAndPyYamlsDumpsOfItLoad) {
  const GridMapFile saved = randomGrid(9, 5, 6);
  ASSERT_EQ(writeGridMap(dir_ + "/g.yaml", saved), "");
  EXPECT_EQ(readText("g.yaml"), kWrittenText);
  for (const char* text : {kPyYamlBlockText, kPyYamlFlowText}) {
    writeText("g.yaml", text);
    GridMapFile loaded;
    ASSERT_EQ(readGridMap(dir_ + "/g.yaml", &loaded), "") << text;
    EXPECT_EQ(loaded.resolution, saved.resolution);
    EXPECT_EQ(loaded.origin_x, saved.origin_x);
    EXPECT_EQ(loaded.origin_y, saved.origin_y);
    EXPECT_EQ(loaded.origin_yaw, saved.origin_yaw);
    EXPECT_EQ(loaded.width, saved.width);
    EXPECT_EQ(loaded.cells, saved.cells);
  }
  // Quoted keys and values, comments, a map_server key this reader does not need.
  writeText("g.yaml",
            "# a hand-edited map\n'image': \"g.pgm\"  # beside this file\n"
            "\"resolution\": '0.05000000074505806'\norigin: [-12.345678901234,\n"
            "  0.42857142857142855, 0.0]\nmode: trinary\nstart_pose: [1, 1, 0]\n");
  GridMapFile loaded;
  ASSERT_EQ(readGridMap(dir_ + "/g.yaml", &loaded), "");
  EXPECT_EQ(loaded.cells, saved.cells);
  EXPECT_EQ(loaded.origin_y, saved.origin_y);
}

// A name YAML would read otherwise written plain is quoted, and loads.
TEST_F(GridMapFileTest, AnImageNameThatNeedsQuotesIsQuoted) {
  const GridMapFile saved = randomGrid(4, 3, 7);
  const std::string path = dir_ + "/office: #2.yaml";
  ASSERT_EQ(writeGridMap(path, saved), "");
  EXPECT_EQ(readText("office: #2.yaml").rfind("image: \"office: #2.pgm\"\n", 0), 0u);
  GridMapFile loaded;
  ASSERT_EQ(readGridMap(path, &loaded), "");
  EXPECT_EQ(loaded.cells, saved.cells);
}

TEST_F(GridMapFileTest, YamlErrorsNameTheLineAndLeaveTheGridAlone) {
  ASSERT_EQ(writeGridMap(dir_ + "/g.yaml", randomGrid(3, 3, 8)), "");
  const GridMapFile kept = randomGrid(2, 2, 3);
  struct Case {
    std::string yaml;
    std::string expected;
  };
  const std::string head = "image: g.pgm\nresolution: 0.05\n";
  const Case cases[] = {
      {head + "origin: [0, 0]\n", "g.yaml:3: origin must be [x, y, yaw], three finite numbers"},
      {head + "origin:\n- 0\n- nan\n- 0\n", "g.yaml:4: origin must be [x, y, yaw]"},
      {head + "origin: {x: 0}\n", "g.yaml:3: origin must be [x, y, yaw]"},
      {head + "origin: [0, 0, 0\n", "g.yaml:3: not valid YAML"},
      {head + "origin: [0, 0, 0]\nresolution: 0.1\n", "g.yaml:4: key 'resolution' given twice"},
      {head + "origin: [0, 0, 0]\nnegate: 2\n", "g.yaml:4: negate must be 0 or 1"},
      {head + "origin: [0, 0, 0]\n\nmode: scale\n", "g.yaml:5: mode 'scale': only trinary"},
      {"image: [g.pgm]\nresolution: 0.05\norigin: [0, 0, 0]\n", "g.yaml:1: image must be a file"},
      {"- image: g.pgm\n", "g.yaml:1: expected map_server's keys"},
      {head + "origin: [0, 0, 0]\n---\nimage: g.pgm\n", "g.yaml:4: more than one YAML document"},
      {head + "origin: [0, 0, 0]\n]\n", "g.yaml:4: not valid YAML"},
      {"{image: g.pgm, resolution: 0.05, origin: [0, 0, 0]},\n",
       "g.yaml:1: more than one YAML document"},
      {"image:\nresolution: 0.05\norigin: [0, 0, 0]\n", "g.yaml: no 'image'"},
      {head, "g.yaml: no 'origin'"},
  };
  for (const Case& c : cases) {
    writeText("g.yaml", c.yaml);
    GridMapFile grid = kept;
    const std::string error = readGridMap(dir_ + "/g.yaml", &grid);
    EXPECT_EQ(error.find(dir_ + "/" + c.expected), 0u) << c.yaml << " → " << error;
    EXPECT_EQ(grid.cells, kept.cells);
  }
}

TEST_F(GridMapFileTest, BrokenFilesAreRefusedNamedAndLeaveTheGridAlone) {
  const GridMapFile saved = randomGrid(10, 10, 2);
  ASSERT_EQ(writeGridMap(dir_ + "/g.yaml", saved), "");
  const std::string image = readText("g.pgm");
  const GridMapFile kept = randomGrid(2, 2, 3);
  auto refused = [&](const std::string& expected_problem) {
    GridMapFile grid = kept;
    const std::string error = readGridMap(dir_ + "/g.yaml", &grid);
    EXPECT_NE(error.find(expected_problem), std::string::npos) << error;
    EXPECT_EQ(grid.cells, kept.cells);
  };
  writeText("g.pgm", image.substr(0, image.size() - 7));
  refused("cut short");
  writeText("g.pgm", "P5\n100000 100000\n255\n");
  refused("at most");
  writeText("g.pgm", "P2\n2 2\n255\n0 0 0 0\n");
  refused("P5");
  std::remove((dir_ + "/g.pgm").c_str());
  refused("cannot open its image");
  writeText("g.pgm", image);
  writeText("g.yaml", "image: g.pgm\nresolution: nan\norigin: [0, 0, 0]\n");
  refused("resolution must be a positive number");
  writeText("g.yaml", "image: g.pgm\nresolution: 0.05\norigin: [0, 0]\n");
  refused("origin must be [x, y, yaw]");
  writeText("g.yaml", "image: g.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nmode: scale\n");
  refused("only trinary");
  writeText("g.yaml", "resolution: 0.05\norigin: [0, 0, 0]\n");
  refused("no 'image'");
  GridMapFile grid;
  EXPECT_NE(readGridMap(dir_ + "/none.yaml", &grid).find("cannot open"), std::string::npos);
}

TEST_F(GridMapFileTest, AGridThatCannotBeWrittenWritesNothing) {
  GridMapFile grid = randomGrid(4, 4, 4);
  grid.cells.pop_back();
  EXPECT_NE(writeGridMap(dir_ + "/bad.yaml", grid).find("nothing written"), std::string::npos);
  grid = randomGrid(4, 4, 4);
  grid.origin_x = std::nan("");
  EXPECT_NE(writeGridMap(dir_ + "/bad.yaml", grid).find("nothing written"), std::string::npos);
  EXPECT_EQ(std::system(("test -z \"$(ls -A '" + dir_ + "')\"").c_str()), 0);
  // A folder that does not exist: the error names the path.
  grid = randomGrid(4, 4, 4);
  EXPECT_NE(writeGridMap(dir_ + "/no/such/dir/g.yaml", grid).find("no/such/dir"),
            std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
