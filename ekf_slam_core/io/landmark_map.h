// The landmark map as a file: what the live node's save_map / load_map
// services and the offline runner's landmarks.yaml hold. Plain text in a
// small YAML subset so that people and yaml tools can read it:
//
//   # comment lines
//   version: 1
//   frame: map
//   count: 1
//   landmarks:
//     - {id: 3, x: 1.25, y: -0.5, covariance: [xx, xy, yx, yy], observations: 7}
//
// `version` is the format's (1; a newer one is refused) and `count` the
// number of landmarks that follow: a file cut short (a full disk, a copy
// interrupted) is refused instead of loading the first part. Files without
// `version` (written before it existed) are read as before, unchecked.
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

constexpr int kLandmarkMapVersion = 1;

// Writes with full double precision (a round trip gives the same numbers).
// Atomic: the text goes to a temporary file in the same directory, is
// flushed to the disk (fsync) and renamed over `path`, so an earlier file
// at `path` survives any failure (a full disk, a crash) unchanged.
// Returns an empty string on success, else the error with the path.
std::string writeLandmarkMap(const std::string& path, const LandmarkMapFile& map);

// Text form of the same (for writeLandmarkMap and tests).
std::string formatLandmarkMap(const LandmarkMapFile& map);

// Parses a whole file; on error returns "<path>:<line>: <problem>" and
// leaves `map` untouched. Duplicate ids, non-finite values, covariances
// that are not symmetric positive definite, values beyond the limits below
// (no building is 1,000 km across) and a landmark count that disagrees
// with `count` are errors.
constexpr double kMaxLandmarkCoordinate = 1e6;  // m, |x| and |y|
constexpr double kMaxLandmarkVariance = 1e6;    // m², each diagonal entry (σ = 1 km)
std::string readLandmarkMap(const std::string& path, LandmarkMapFile* map);
std::string parseLandmarkMap(const std::string& text, const std::string& source,
                             LandmarkMapFile* map);

}  // namespace ekf_slam
