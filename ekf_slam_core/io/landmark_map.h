// The landmark map as a file: what the live node's save_map / load_map
// services and the offline runner's landmarks.yaml hold. Plain text in a
// small YAML subset so that people and yaml tools can read it:
//
//   # comment lines
//   frame: map
//   landmarks:
//     - {id: 3, x: 1.25, y: -0.5, covariance: [xx, xy, yx, yy], observations: 7}
//
// Units: m for x, y; m² for the covariance (the full 2×2 marginal of the
// landmark in the map frame, row-major). The reader also accepts the
// three-value form [xx, xy, yy] written by ekf_slam_offline, and a missing
// `observations` (then 2: not tentative). No ROS, no yaml-cpp: the core
// stays dependency-free.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

struct LandmarkRecord {
  int id = -1;
  Vector2 position = Vector2::Zero();    // m, map frame
  Matrix2 covariance = Matrix2::Zero();  // m², of position
  int observations = 2;
};

struct LandmarkMapFile {
  std::string frame = "map";
  std::vector<LandmarkRecord> landmarks;
};

// Writes with full double precision (a round trip gives the same numbers).
// Returns an empty string on success, else the error with the path.
std::string writeLandmarkMap(const std::string& path, const LandmarkMapFile& map);

// Text form of the same (for writeLandmarkMap and tests).
std::string formatLandmarkMap(const LandmarkMapFile& map);

// Parses a whole file; on error returns "<path>:<line>: <problem>" and
// leaves `map` untouched. Duplicate ids, non-finite values and covariances
// that are not symmetric positive definite are errors.
std::string readLandmarkMap(const std::string& path, LandmarkMapFile* map);
std::string parseLandmarkMap(const std::string& text, const std::string& source,
                             LandmarkMapFile* map);

}  // namespace ekf_slam
