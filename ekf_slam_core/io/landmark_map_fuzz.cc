// libFuzzer target: the landmark-map loader (what ~load_map and a prior map
// file go through) on arbitrary text. Properties: no crash, no UB; a map
// that loads holds only finite values within the bounds, symmetric
// positive definite covariances (positive variances) within the bounds,
// lines in normal form, ordered extents, ids unique across all kinds and
// endpoints that name its points; and writing it out and reading it back
// gives the same map, bit for bit.
// Built by `make fuzz` (clang, -DEKF_SLAM_FUZZ=ON).
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>

#include "ekf_slam_core/io/landmark_map.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ekf_slam;
  const std::string text(reinterpret_cast<const char*>(data), size);
  LandmarkMapFile map;
  map.frame = "untouched";
  const std::string error = parseLandmarkMap(text, "fuzz", &map);
  if (!error.empty()) {
    assert(error.rfind("fuzz", 0) == 0);  // names the source
    assert(map.frame == "untouched" && map.landmarks.empty());
    return 0;
  }
  auto validCovariance = [](const Matrix2& c, double max_first, double max_second) {
    return c.allFinite() && std::abs(c(0, 1) - c(1, 0)) <= 1e-9 * (1.0 + c.cwiseAbs().maxCoeff()) &&
           c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0 && c(0, 0) <= max_first &&
           c(1, 1) <= max_second;
  };
  std::set<int> ids, point_ids;
  for (const LandmarkRecord& landmark : map.landmarks) {
    assert(ids.insert(landmark.id).second);
    point_ids.insert(landmark.id);
    assert(landmark.position.allFinite());
    assert(std::abs(landmark.position.x()) <= kMaxLandmarkCoordinate);
    assert(std::abs(landmark.position.y()) <= kMaxLandmarkCoordinate);
    assert(validCovariance(landmark.covariance, kMaxLandmarkVariance, kMaxLandmarkVariance));
  }
  for (const LineLandmarkRecord& line : map.lines) {
    assert(ids.insert(line.id).second);
    assert(std::isfinite(line.p) && line.p >= 0.0 && line.p <= kMaxLandmarkCoordinate);
    assert(std::isfinite(line.theta) && std::abs(line.theta) <= kPi);
    assert(validCovariance(line.covariance, kMaxLandmarkVariance, kMaxLandmarkAngleVariance));
    if (line.has_extent) {
      assert(std::isfinite(line.s_min) && std::isfinite(line.s_max) && line.s_min <= line.s_max);
      assert(std::abs(line.s_min) <= kMaxLandmarkCoordinate);
      assert(std::abs(line.s_max) <= kMaxLandmarkCoordinate);
    }
  }
  for (const LineAngleRecord& direction : map.line_angles) {
    assert(ids.insert(direction.id).second);
    assert(std::isfinite(direction.theta) && std::abs(direction.theta) <= kPi);
    assert(direction.variance > 0.0 && direction.variance <= kMaxLandmarkAngleVariance);
    for (int endpoint : direction.endpoint_ids) assert(endpoint == -1 || point_ids.count(endpoint));
  }
  LandmarkMapFile again;
  const std::string reread = parseLandmarkMap(formatLandmarkMap(map), "round trip", &again);
  assert(reread.empty());
  assert(again.frame == map.frame);
  assert(again.landmarks.size() == map.landmarks.size());
  assert(again.lines.size() == map.lines.size());
  assert(again.line_angles.size() == map.line_angles.size());
  for (size_t i = 0; i < map.landmarks.size(); ++i) {
    const LandmarkRecord& a = map.landmarks[i];
    const LandmarkRecord& b = again.landmarks[i];
    assert(a.id == b.id && a.observations == b.observations);
    assert(a.position == b.position && a.covariance == b.covariance);
  }
  for (size_t i = 0; i < map.lines.size(); ++i) {
    const LineLandmarkRecord& a = map.lines[i];
    const LineLandmarkRecord& b = again.lines[i];
    assert(a.id == b.id && a.observations == b.observations && a.has_extent == b.has_extent);
    assert(a.p == b.p && a.theta == b.theta && a.covariance == b.covariance);
    assert(!a.has_extent || (a.s_min == b.s_min && a.s_max == b.s_max));
  }
  for (size_t i = 0; i < map.line_angles.size(); ++i) {
    const LineAngleRecord& a = map.line_angles[i];
    const LineAngleRecord& b = again.line_angles[i];
    assert(a.id == b.id && a.observations == b.observations);
    assert(a.theta == b.theta && a.variance == b.variance);
    assert(a.endpoint_ids[0] == b.endpoint_ids[0] && a.endpoint_ids[1] == b.endpoint_ids[1]);
  }
  return 0;
}
