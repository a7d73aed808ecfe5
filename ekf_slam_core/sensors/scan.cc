#include "ekf_slam_core/sensors/scan.h"

#include <algorithm>
#include <sstream>

namespace ekf_slam {

int countValidReadings(const Scan& scan) {
  int count = 0;
  for (int i = 0; i < scan.size(); ++i) count += scan.isValid(i) ? 1 : 0;
  return count;
}

Scan mirroredScan(const Scan& scan) {
  Scan mirrored = scan;
  std::reverse(mirrored.ranges.begin(), mirrored.ranges.end());
  const int last = std::max(scan.size() - 1, 0);
  mirrored.angle_min = -(scan.angle_min + last * scan.angle_increment);
  return mirrored;
}

std::string validateScan(const Scan& scan) {
  std::ostringstream error;
  if (!std::isfinite(scan.angle_min)) {
    error << "Scan.angle_min must be finite, got " << scan.angle_min;
  } else if (!std::isfinite(scan.angle_increment) || scan.angle_increment == 0.0) {
    error << "Scan.angle_increment must be finite and non-zero, got " << scan.angle_increment;
  } else if (!std::isfinite(scan.range_min) || scan.range_min < 0.0) {
    error << "Scan.range_min must be finite and >= 0, got " << scan.range_min;
  } else if (!(scan.range_max > scan.range_min)) {
    error << "Scan.range_max must be greater than range_min (" << scan.range_min << "), got "
          << scan.range_max;
  } else if (scan.size() > 1 && !std::isfinite(scan.angle(scan.size() - 1))) {
    // Each increment is finite but the sweep is not: angle_min plus
    // (n - 1) increments overflows, so the last beams have no bearing.
    error << "Scan.angle_increment " << scan.angle_increment << " over " << scan.size()
          << " beams gives a last bearing of " << scan.angle(scan.size() - 1);
  } else if (!std::isfinite(scan.stamp)) {
    error << "Scan.stamp must be finite, got " << scan.stamp;
  }
  return error.str();
}

}  // namespace ekf_slam
