// libFuzzer target: a sensor_msgs/LaserScan as a driver or a bag may deliver
// it (any angle fields, any range count, NaN/inf/negative/huge readings,
// any stamp), through the node's boundary (the range-count check, the
// conversion to the core's Scan, the geometry check) into the first stage
// of the pipeline, feature extraction. Properties: no crash, no UB, and
// whatever passes the boundary yields features that validateFeatureSet
// accepts, which is what the filter requires of its input.
// Built by `make fuzz` (clang, -DEKF_SLAM_FUZZ=ON). The whole pipeline
// behind it is fuzzed by slam_pipeline_fuzz (fewer inputs per second).
#include <fuzzer/FuzzedDataProvider.h>
#include <sensor_msgs/LaserScan.h>

#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_ros/conversions/scan_conversion.h"

namespace {

// A float chosen by the input: an ordinary value or a hostile one.
float pick(FuzzedDataProvider& input, float ordinary) {
  switch (input.ConsumeIntegralInRange<int>(0, 11)) {
    case 0:
      return std::numeric_limits<float>::quiet_NaN();
    case 1:
      return std::numeric_limits<float>::infinity();
    case 2:
      return -std::numeric_limits<float>::infinity();
    case 3:
      return 0.0f;
    case 4:
      return -ordinary;
    case 5:
      return std::numeric_limits<float>::max();
    case 6:
      return std::numeric_limits<float>::denorm_min();
    case 7:
      return input.ConsumeFloatingPoint<float>();
    default:
      return ordinary;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ekf_slam;
  FuzzedDataProvider input(data, size);
  sensor_msgs::LaserScan message;
  message.header.stamp.sec = input.ConsumeIntegral<uint32_t>();
  message.header.stamp.nsec = input.ConsumeIntegralInRange<uint32_t>(0, 999999999);
  const int beams = input.ConsumeIntegralInRange<int>(0, 181);
  const float span = static_cast<float>(kPi) * input.ConsumeIntegralInRange<int>(1, 4) / 4.0f;
  message.angle_min = pick(input, -span / 2.0f);
  message.angle_increment = pick(input, beams > 1 ? span / (beams - 1) : 0.01f);
  message.angle_max = pick(input, span / 2.0f);
  message.range_min = pick(input, 0.02f);
  message.range_max = pick(input, input.ConsumeBool() ? 8.18f : 80.0f);
  // The reported count may differ from what the angles give.
  const int count = input.ConsumeBool() ? beams : input.ConsumeIntegralInRange<int>(0, 200);
  message.ranges.resize(count);
  // A room-like profile (walls with corners), then hostile readings.
  const float wall = 1.0f + input.ConsumeIntegralInRange<int>(0, 60) * 0.1f;
  for (int i = 0; i < count; ++i) {
    const float bearing = -span / 2.0f + i * (count > 1 ? span / (count - 1) : 0.0f);
    message.ranges[i] = std::min(wall / std::max(std::abs(std::cos(bearing)), 0.05f), 40.0f);
  }
  const int damaged = count > 0 ? input.ConsumeIntegralInRange<int>(0, 16) : 0;
  for (int j = 0; j < damaged; ++j) {
    const int i = input.ConsumeIntegralInRange<int>(0, count - 1);
    message.ranges[i] = pick(input, message.ranges[i]);
  }
  while (input.remaining_bytes() >= sizeof(float) && !message.ranges.empty()) {
    const int i = input.ConsumeIntegralInRange<int>(0, count - 1);
    message.ranges[i] = input.ConsumeFloatingPoint<float>();
  }

  // The node's boundary, in the node's order.
  if (!ros_conversions::rangeCountError(message).empty()) return 0;
  const Scan scan = ros_conversions::fromLaserScan(message);
  assert(scan.size() == count);
  if (!validateScan(scan).empty()) return 0;
  if (countValidReadings(scan) < 10) return 0;
  const FeatureSet features = extractFeatures(scan, FeatureOptions());
  const std::string invalid = validateFeatureSet(features);
  if (!invalid.empty()) std::fprintf(stderr, "laser_scan_fuzz: %s\n", invalid.c_str());
  assert(invalid.empty());
  return 0;
}
