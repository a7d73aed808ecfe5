// libFuzzer target: the landmark-map loader (what ~load_map and a prior map
// file go through) on arbitrary text. Properties: no crash, no UB; a map
// that loads holds only finite positions within the bounds, symmetric
// positive definite covariances within the bounds and unique ids; and
// writing it out and reading it back gives the same map, bit for bit.
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
  std::set<int> ids;
  for (const LandmarkRecord& landmark : map.landmarks) {
    assert(ids.insert(landmark.id).second);
    assert(landmark.position.allFinite());
    assert(std::abs(landmark.position.x()) <= kMaxLandmarkCoordinate);
    assert(std::abs(landmark.position.y()) <= kMaxLandmarkCoordinate);
    const Matrix2& c = landmark.covariance;
    assert(c.allFinite());
    assert(std::abs(c(0, 1) - c(1, 0)) <= 1e-9 * (1.0 + c.cwiseAbs().maxCoeff()));
    assert(c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0);
    assert(c(0, 0) <= kMaxLandmarkVariance && c(1, 1) <= kMaxLandmarkVariance);
  }
  LandmarkMapFile again;
  const std::string reread = parseLandmarkMap(formatLandmarkMap(map), "round trip", &again);
  assert(reread.empty());
  assert(again.frame == map.frame);
  assert(again.landmarks.size() == map.landmarks.size());
  for (size_t i = 0; i < map.landmarks.size(); ++i) {
    const LandmarkRecord& a = map.landmarks[i];
    const LandmarkRecord& b = again.landmarks[i];
    assert(a.id == b.id && a.observations == b.observations);
    assert(a.position == b.position && a.covariance == b.covariance);
  }
  return 0;
}
