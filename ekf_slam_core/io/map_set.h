// A saved map: the landmark file and the occupancy grid beside it
// ("office.yaml" → "office_grid.yaml", whose image is "office_grid.pgm"),
// written as one set (file_set.h) so that a load never pairs the files of
// two saves.
#pragma once

#include <optional>
#include <string>

#include "ekf_slam_core/io/grid_map_file.h"
#include "ekf_slam_core/io/landmark_map.h"

namespace ekf_slam {

struct MapSetPaths {
  std::string landmarks;
  std::string grid;   // the map_server YAML
  std::string image;  // the grid's image, named by `grid`
};

// The files of the map saved as `landmark_path`.
MapSetPaths mapSetPaths(const std::string& landmark_path);

// Writes the set: the landmarks and, if given, the grid; without one, a
// grid an earlier save left there is removed. A path that is a directory,
// a device or a pipe refuses the save before anything is written. Empty on
// success, else the problem.
std::string writeMapSet(const std::string& landmark_path, const LandmarkMapFile& landmarks,
                        const std::optional<GridMapFile>& grid);

// Completes a save of the set that stopped after its commit, and removes
// the temporaries stopped saves left; for every reader, before it reads.
std::string finishInterruptedMapSave(const std::string& landmark_path);

}  // namespace ekf_slam
