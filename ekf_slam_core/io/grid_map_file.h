// An occupancy grid as map_server saves and loads it: a PGM image and a
// YAML file naming it,
//
//   image: office_grid.pgm      # beside the YAML file
//   resolution: 0.05            # m per cell
//   origin: [x, y, yaw]         # the lower-left cell's corner in the map frame
//   negate: 0
//   occupied_thresh: 0.65
//   free_thresh: 0.196
//
// The grid holds the values of a nav_msgs/OccupancyGrid: -1 unknown, 0 free,
// 100 occupied (map_server's trinary mode). Written as pixels 205, 254 and
// 0, which map_server, and readGridMap, read back as the same three values,
// so a save and a load give the grid bit for bit. The YAML file is read
// with yaml-cpp, as map_server reads it: any YAML of the same content loads
// (block or flow style, `origin` as a block list, keys in any order or
// quoted, comments). No ROS.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ekf_slam_core/io/file_set.h"

namespace ekf_slam {

struct GridMapFile {
  double resolution = 0.05;                                 // m per cell
  double origin_x = 0.0, origin_y = 0.0, origin_yaw = 0.0;  // m, m, rad
  int width = 0, height = 0;                                // cells
  std::vector<int8_t> cells;  // width × height, row by row from the lower left
};

// Largest grid read or written: 10⁸ cells (100 MB), 500 km² at 5 cm.
constexpr long kMaxGridCells = 100000000;

// The two files of `grid` saved as `yaml_path`, appended to `files`: the
// image beside it (the same name, .pgm instead of .yaml), then the
// map_server YAML that names it. Values other than -1, 0 and 100 are
// written as map_server would threshold them. An image name that YAML
// would read differently written plain (one with ': ' or ' #', say) is
// double-quoted. Empty on success, else the problem (nothing appended).
std::string formatGridMap(const std::string& yaml_path, const GridMapFile& grid,
                          std::vector<FileSetEntry>* files);
// Writes both as one set (file_set.h; the journal is journalFor(yaml_path)).
std::string writeGridMap(const std::string& yaml_path, const GridMapFile& grid);
// The image writeGridMap writes beside `yaml_path`.
std::string imagePathFor(const std::string& yaml_path);

// Reads a map_server map (trinary mode; a binary PGM, P5). On error returns
// "<path>:<line>: <problem>" ("<path>: <problem>" when no line is at fault)
// and leaves `grid` untouched: text that is not YAML, a key given twice, a
// missing or unreadable image, a size that disagrees with the data, a
// resolution or origin that is not finite and positive where it must be, a
// mode other than trinary, more than kMaxGridCells cells.
std::string readGridMap(const std::string& yaml_path, GridMapFile* grid);

}  // namespace ekf_slam
