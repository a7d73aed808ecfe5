#include "ekf_slam_core/sensors/scan_merge.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace ekf_slam {
namespace {

constexpr double kMinIncrement = 1e-4;       // rad: 62,832 beams
constexpr double kMaxIncrement = kPi / 4.0;  // rad: 8 beams

// Empty when `mounted` can be merged, else the problem, prefixed by `name`.
std::string checkMounted(const MountedScan& mounted, const char* name) {
  std::ostringstream error;
  if (mounted.scan == nullptr) {
    error << name << " scan: missing (null)";
  } else if (!mounted.mount.allFinite()) {
    error << name << " scan: its mount must be finite, got (" << mounted.mount.x << ", "
          << mounted.mount.y << ", " << mounted.mount.theta << ")";
  } else if (mounted.scan->size() > 0) {
    const std::string geometry = validateScan(*mounted.scan);
    if (!geometry.empty()) error << name << " scan: " << geometry;
  }
  return error.str();
}

}  // namespace

std::string mergeScans(const MountedScan& first, const MountedScan& second,
                       const Pose2& second_motion, const ScanMergeOptions& options, Scan* merged) {
  const double increment = options.angle_increment;
  if (!(increment >= kMinIncrement && increment <= kMaxIncrement)) {
    std::ostringstream error;
    error << "ScanMergeOptions.angle_increment must be in [" << kMinIncrement << ", "
          << kMaxIncrement << "] rad, got " << increment;
    return error.str();
  }
  std::string error = checkMounted(first, "first");
  if (error.empty()) error = checkMounted(second, "second");
  if (!error.empty()) return error;
  if (!second_motion.allFinite()) {
    std::ostringstream text;
    text << "the motion between the scans must be finite, got (" << second_motion.x << ", "
         << second_motion.y << ", " << second_motion.theta << ")";
    return text.str();
  }

  const int beams = std::max(1, static_cast<int>(std::lround(2.0 * kPi / increment)));
  Scan out;
  out.angle_min = -kPi;
  out.angle_increment = 2.0 * kPi / beams;
  out.range_min = 0.0;
  out.range_max = 0.0;
  out.stamp = first.scan->stamp;
  out.merged = true;
  out.ranges.assign(beams, std::numeric_limits<double>::infinity());

  // Each scan's laser in the first scan's base_link.
  const MountedScan* scans[] = {&first, &second};
  const Pose2 lasers[] = {first.mount, compose(second_motion, second.mount)};
  const double reach[] = {first.mount.translation().norm(),
                          second.mount.translation().norm() + second_motion.translation().norm()};
  double farthest = 0.0;  // of the points kept
  for (int k = 0; k < 2; ++k) {
    const Scan& scan = *scans[k]->scan;
    if (scan.size() == 0) continue;
    const double limit = scan.range_max + reach[k];
    if (std::isfinite(limit)) out.range_max = std::max(out.range_max, limit);
    const Pose2& laser = lasers[k];
    for (int i = 0; i < scan.size(); ++i) {
      if (!scan.isValid(i)) continue;
      const double bearing = scan.angle(i);
      const Vector2 point =
          transformFrom(laser, scan.ranges[i] * Vector2(std::cos(bearing), std::sin(bearing)));
      const double range = point.norm();
      // A point at the origin has no bearing; a non-finite one no place.
      if (!std::isfinite(range) || !(range > 0.0)) continue;
      const double angle = std::atan2(point.y(), point.x());  // [-π, π]
      int beam = static_cast<int>(std::floor((angle + kPi) / out.angle_increment + 0.5));
      if (beam >= beams) beam -= beams;  // +π is the beam at −π
      if (beam < 0 || beam >= beams) continue;
      if (range < out.ranges[beam]) {
        out.ranges[beam] = range;
        farthest = std::max(farthest, range);
      }
    }
  }
  // Every kept reading below range_max, also when a laser's range_max is
  // +inf; a positive, finite range_max when nothing bounds it.
  if (farthest >= out.range_max) {
    out.range_max = std::nextafter(farthest, std::numeric_limits<double>::infinity());
  }
  if (!(out.range_max > 0.0) || !std::isfinite(out.range_max)) {
    out.range_max = std::numeric_limits<double>::max();
  }
  *merged = std::move(out);
  return "";
}

}  // namespace ekf_slam
