// One planar laser sweep as the core sees it (no ROS): the LMS200 or a
// simulated scanner. ekf_slam_ros/conversions turns a sensor_msgs/LaserScan
// into this struct at the boundary.
//
// Frame: the laser (sensor) frame, x forward, y left (REP-103). Beam i points
// at bearing angle(i) = angle_min + i * angle_increment (rad, counter-clockwise
// from the laser x axis) and reports the distance ranges[i] (m).
//
// Invalid-reading convention (REP-117 plus the LMS200 logs): a reading is
// used only when it is finite, >= range_min and < range_max. So NaN
// (erroneous), -inf (too close), +inf (no return), and every value at or above
// range_max are "no valid return". In the Freiburg logs range_max is 80 m and
// 81.83 m / 81.91 m encode "no return"; the LMS200's reserved error codes
// (dazzle, no echo, ...) all lie at or above its range_max in cm or mm mode,
// so they fall out by the same rule. Nothing is ever removed from `ranges`:
// beam indices stay aligned with bearings.
#pragma once

#include <cmath>
#include <string>
#include <vector>

namespace ekf_slam {

struct Scan {
  std::vector<double> ranges;    // m, one per beam; invalid values allowed (see above)
  double angle_min = 0.0;        // rad, bearing of beam 0 in the laser frame
  double angle_increment = 0.0;  // rad, bearing step between beams (may be negative)
  double range_min = 0.0;        // m, readings below are invalid
  double range_max = 0.0;        // m, readings at or above are invalid ("no return")
  double stamp = 0.0;            // s, acquisition time of the sweep (data time, not now())
  // Readings of several lasers put into the beams of one virtual laser at
  // the origin (scan_merge.h), false for a laser's own scan. The feature
  // extraction then counts each bearing's rounding to its beam as noise
  // (uniform over ±half a beam: variance angle_increment² / 12) and places
  // no object end at an occlusion edge: the beam beyond it was not cast
  // from where the end was seen.
  bool merged = false;

  int size() const { return static_cast<int>(ranges.size()); }
  double angle(int i) const { return angle_min + i * angle_increment; }
  // True when beam i carries a usable range (finite, in [range_min, range_max)).
  bool isValid(int i) const {
    const double r = ranges[i];
    return std::isfinite(r) && r >= range_min && r < range_max;
  }
};

// The scan a laser mounted upside down gives, as an upright laser at the
// same place and heading would report it: a beam at bearing α in the
// inverted laser's frame points at −α in the upright one. The beams are
// reversed so that the bearings still increase; the ranges are untouched.
// Mirroring twice gives the scan back.
Scan mirroredScan(const Scan& scan);

// One beam of a laser whose scan plane is tilted from the floor's. The
// laser's rotation from a level laser at the same place and heading is
// R_y(pitch) R_x(roll), ROS's roll and pitch (REP-103: a positive pitch
// tips the front down, a positive roll the left side up). The beam at
// `bearing` in the laser's own frame points, seen from above, at
// `level_bearing`; each metre along it covers `horizontal` metres over the
// floor and climbs `rise` metres.
struct TiltedBeam {
  double level_bearing = 0.0;  // rad
  double horizontal = 1.0;     // cos of the beam's elevation
  double rise = 0.0;           // sin of the beam's elevation
};
TiltedBeam tiltedBeam(double bearing, double roll, double pitch);

// The scan a level laser at the same place and heading would report, from
// the scan of one tilted by `roll` and `pitch` (TiltedBeam): walls taller
// than the beams are where the level laser would see them. Each reading is
// shortened to its distance over the floor and moved to its bearing seen
// from above; the scan's own bearings are then filled from the two moved
// beams that enclose each, linearly where both lie on one surface (ranges
// within 5 cm + 5 %), else from the nearer. A bearing moves by about
// tilt² / 4 (0.02° at 2°), far less than a beam step, so every beam stays
// between its neighbours; the fill is exact to 0.2 mm on a wall 10 m away,
// and cuts a corner by up to 4 mm in the beam beside it. Invalid readings
// stay invalid. A level mount (both angles exactly 0) gives the scan back
// unchanged, bit for bit.
Scan levelledScan(const Scan& scan, double roll, double pitch);

// Number of beams that carry a usable range.
int countValidReadings(const Scan& scan);

// Empty when the scan's geometry is usable, otherwise a message naming the
// bad field (e.g. "Scan.angle_increment must be finite and non-zero, got 0").
// Bad range values are not an error: they are invalid readings.
std::string validateScan(const Scan& scan);

}  // namespace ekf_slam
