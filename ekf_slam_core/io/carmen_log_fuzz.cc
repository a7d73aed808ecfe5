// libFuzzer target: the CARMEN log reader on arbitrary text, line by line
// as readCarmenLog reads a file. Properties: no crash, no UB, no unbounded
// allocation (the reading count is capped), and every line either parses to
// one message of the kind it names or is refused with a reason; a parsed
// scan holds exactly the readings its count announced.
// Built by `make fuzz` (clang, -DEKF_SLAM_FUZZ=ON).
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "ekf_slam_core/io/carmen_log.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ekf_slam;
  std::istringstream text(std::string(reinterpret_cast<const char*>(data), size));
  std::string line, kind;
  while (std::getline(text, line)) {
    CarmenLaser laser;
    CarmenOdometry odometry;
    const std::string error = parseCarmenLine(line, 80.0, &kind, &laser, &odometry);
    if (!error.empty()) {
      assert(kind.empty());
      continue;
    }
    if (kind == "FLASER") {
      assert(line.find("FLASER") != std::string::npos);
      assert(laser.scan.range_max == 80.0);
      assert(laser.scan.size() <= 100000);
    } else if (kind == "ROBOTLASER1") {
      assert(laser.scan.range_max <= 80.0 || !(laser.scan.range_max == laser.scan.range_max));
      assert(laser.scan.size() <= 100000);
    } else {
      assert(kind.empty() || kind == "ODOM");
      assert(laser.scan.ranges.empty());
    }
  }
  return 0;
}
