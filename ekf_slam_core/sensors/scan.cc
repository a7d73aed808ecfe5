#include "ekf_slam_core/sensors/scan.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ekf_slam_core/geometry/angle.h"

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

TiltedBeam tiltedBeam(double bearing, double roll, double pitch) {
  // d = R_y(pitch) R_x(roll) (cos b, sin b, 0).
  const double c = std::cos(bearing), s = std::sin(bearing);
  const double x = c * std::cos(pitch) + s * std::sin(roll) * std::sin(pitch);
  const double y = s * std::cos(roll);
  TiltedBeam beam;
  beam.level_bearing = std::atan2(y, x);
  beam.horizontal = std::hypot(x, y);
  beam.rise = -c * std::sin(pitch) + s * std::sin(roll) * std::cos(pitch);
  return beam;
}

Scan levelledScan(const Scan& scan, double roll, double pitch) {
  if (roll == 0.0 && pitch == 0.0) return scan;
  const int n = scan.size();
  // Along the sweep: bearings counted in the direction the beams run, so
  // that they increase whatever the increment's sign.
  const double sweep = scan.angle_increment < 0.0 ? -1.0 : 1.0;
  std::vector<double> along(n), range(n);
  for (int i = 0; i < n; ++i) {
    const TiltedBeam beam = tiltedBeam(scan.angle(i), roll, pitch);
    // The level bearing, unwrapped to lie next to the beam's own.
    along[i] = sweep * (scan.angle(i) + wrapAngle(beam.level_bearing - scan.angle(i)));
    range[i] = scan.isValid(i) ? scan.ranges[i] * beam.horizontal : scan.ranges[i];
  }
  Scan levelled = scan;
  auto valid = [&](int j) {
    return std::isfinite(range[j]) && range[j] >= scan.range_min && range[j] < scan.range_max;
  };
  int j = 0;  // the last moved beam at or before the wanted bearing
  for (int i = 0; i < n; ++i) {
    const double wanted = sweep * scan.angle(i);
    while (j + 1 < n && along[j + 1] <= wanted) ++j;
    if (along[j] > wanted || j + 1 >= n) {  // before the first or past the last moved beam
      levelled.ranges[i] = range[j];
      continue;
    }
    const int k = j + 1;
    const double t = (wanted - along[j]) / (along[k] - along[j]);
    if (valid(j) && valid(k) &&
        std::abs(range[j] - range[k]) <= 0.05 + 0.05 * std::min(range[j], range[k])) {
      levelled.ranges[i] = range[j] + t * (range[k] - range[j]);
    } else {
      levelled.ranges[i] = t < 0.5 ? range[j] : range[k];
    }
  }
  return levelled;
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
