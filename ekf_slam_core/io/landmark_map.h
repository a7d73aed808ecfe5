// The landmark map as a file: what the live node's save_map / load_map
// services and the offline runner's landmarks.yaml hold. YAML, so that
// people and yaml tools can read and edit it. The writer puts one entry on
// a line:
//
//   # comment lines
//   version: 2
//   frame: map
//   count: 3
//   landmarks:
//     - {id: 3, x: 1.25, y: -0.5, covariance: [xx, xy, yx, yy], observations: 7}
//   lines:
//     - {id: 5, p: 2.5, theta: 1.57, covariance: [pp, pt, tp, tt], observations: 12,
//        extent: [-1.5, 3.0]}
//   line_angles:
//     - {id: 8, theta: -1.57, variance: 1e-4, observations: 9, endpoints: [3, -1]}
//
// and the reader (yaml-cpp) takes any YAML of the same content: block or
// flow style, keys in any order or quoted, comments anywhere, numbers
// quoted or not (what PyYAML's load and dump of the file gives loads).
// `landmarks` are the points (x, y); `lines` the (p, θ) line landmarks,
// x cos θ + y sin θ = p; `line_angles` the θ-only ones (the normal's
// direction θ; the offset comes from the point landmarks named in
// `endpoints`, -1 for none). Ids are unique across all three lists, and
// every endpoint id names a point of `landmarks`.
//
// `version` is the format's (2; a newer one is refused) and `count` the
// number of landmarks of all kinds that follow: a file cut short (a full
// disk, a copy interrupted) is refused instead of loading the first part.
// Version 2 needs all three lists (an empty one as `lines: []`, or `lines:`
// alone); version 1 files hold points only; files without `version`
// (written before it existed) are read as version 1 without `count`.
//
// Units, all in the map frame: m for x, y, p and the extent; rad for θ,
// normalised (p >= 0, θ in [-π, π]); covariances are the full 2×2 marginal
// of the landmark, row-major: m² for points, (m², m·rad, m·rad, rad²) for
// lines; `variance` of a θ-only line in rad². `extent` [s_min, s_max] is
// the stretch of the line that was seen, along d = (−sin θ, cos θ) from the
// foot point p·(cos θ, sin θ) (optional: absent when unknown). The reader
// also accepts the three-value form [xx, xy, yy] of older offline runs, and
// a missing `observations` (then 2: not tentative). No ROS; yaml-cpp stays
// inside the .cc files.
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

// A (p, θ) line landmark.
struct LineLandmarkRecord {
  int id = -1;
  double p = 0.0;                        // m, >= 0
  double theta = 0.0;                    // rad, the normal's direction, [-π, π]
  Matrix2 covariance = Matrix2::Zero();  // of (p, θ): m², m·rad, rad²
  int observations = 2;
  bool has_extent = false;  // false: the seen stretch is unknown
  double s_min = 0.0;       // m, along (−sin θ, cos θ) from the foot point
  double s_max = 0.0;       // m, s_min <= s_max
};

// A θ-only line landmark.
struct LineAngleRecord {
  int id = -1;
  double theta = 0.0;     // rad, [-π, π]
  double variance = 0.0;  // rad²
  int observations = 2;
  int endpoint_ids[2] = {-1, -1};  // point landmarks on the line, -1: none
};

struct LandmarkMapFile {
  std::string frame = "map";
  std::vector<LandmarkRecord> landmarks;  // points
  std::vector<LineLandmarkRecord> lines;
  std::vector<LineAngleRecord> line_angles;

  size_t size() const { return landmarks.size() + lines.size() + line_angles.size(); }
};

constexpr int kLandmarkMapVersion = 2;

// Writes with full double precision (a round trip gives the same numbers);
// a frame that YAML would read differently written plain (one with a '#',
// a ': ', a line break, or "null") is double-quoted.
// Atomic: the text goes to a temporary file in the same directory, is
// flushed to the disk (fsync) and renamed over `path`, so an earlier file
// at `path` survives any failure (a full disk, a crash) unchanged.
// Returns an empty string on success, else the error with the path.
std::string writeLandmarkMap(const std::string& path, const LandmarkMapFile& map);

// Text form of the same (for writeLandmarkMap and tests).
std::string formatLandmarkMap(const LandmarkMapFile& map);

// Parses a whole file; on error returns "<path>:<line>: <problem>" (the
// 1-based line where the value at fault starts; "<path>: <problem>" for
// what concerns the whole file, such as a count that disagrees) and leaves
// `map` untouched. Text that is not YAML (yaml-cpp's message and line),
// more than one YAML document, a key given twice, unknown keys, duplicate
// ids (across all kinds), non-finite values, covariances that are not
// symmetric positive definite, values beyond the limits below (no building
// is 1,000 km across), p < 0, θ outside [-π, π], an extent with
// s_min > s_max, endpoint ids that name no point of the file (or the same
// point twice) and a landmark count that disagrees with `count` are errors.
constexpr double kMaxLandmarkCoordinate = 1e6;  // m, |x|, |y|, p and |s|
constexpr double kMaxLandmarkVariance = 1e6;    // m², each diagonal entry (σ = 1 km)
// rad², of θ: σ = π, a direction not known at all.
constexpr double kMaxLandmarkAngleVariance = kPi * kPi;
std::string readLandmarkMap(const std::string& path, LandmarkMapFile* map);
std::string parseLandmarkMap(const std::string& text, const std::string& source,
                             LandmarkMapFile* map);

}  // namespace ekf_slam
