// The thesis's manual calibration of the laser mount (§3.4.1), derived
// anew (docs/maths.md, section 10): a reference point feature (a convex
// corner) seen before and after two known motions of the robot.
//
// With the mount (t, ψ) = base_link → laser and the feature at p in the
// robot frame, the laser sees z = R(ψ)ᵀ (p − t).
// - Yaw: a straight move of the robot by d along its x axis turns p into
//   p − (d, 0), so z − z' = d (cos ψ, −sin ψ): ψ = atan2(z'_y − z_y,
//   z_x − z'_x), whatever t and whatever the exact d (|z − z'| checks it).
//   The thesis's eq. 3.43 is this with its robot moving along y.
// - Translation: a turn on the spot by φ turns p into R(φ)ᵀ p. With
//   q = R(ψ) z = p − t and q' = R(ψ) z' = R(φ)ᵀ p − t,
//   p = (I − R(φ)ᵀ)⁻¹ (q − q') and t = p − q (eqs. 3.44–3.55 solved in
//   closed form; φ must not be near 0).
// - Pitch or roll: two objects of heights h1 < h2 whose tops the beam just
//   grazes, d apart along the beam: atan((h2 − h1) / d) (eq. 3.36).
// Each sighting is the mean of N scans' corner estimates (the thesis's
// "Monte Carlo experiments"); the standard deviations follow from their
// spread. No ROS.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

// The beam's tilt (rad, positive: rising away from the scanner) from two
// objects whose tops it grazes: h1 the nearer's height, h2 the farther's,
// d their distance along the beam (eq. 3.36). Pitch with the objects
// straight ahead, roll with them at the side.
double beamTilt(double h1, double h2, double d);

// A reference feature averaged over several scans, in the laser frame.
struct FeatureSighting {
  bool ok = false;
  Vector2 mean = Vector2::Zero();
  Matrix2 covariance = Matrix2::Zero();  // of the mean
  int scans = 0;                         // scans in which the feature was found
  std::string message;                   // why it failed
};

// The corner (PointKind::kCorner: two fitted lines meeting) nearest to
// `near` (laser frame) within `gate` metres in each scan, averaged. Scans
// without one are skipped; fewer than half of them with one, or sightings
// that scatter by more than 3 cm (two corners taken in turn), is a failure.
FeatureSighting sightFeature(const std::vector<Scan>& scans, const Vector2& near, double gate,
                             const FeatureOptions& options = {});

struct YawCalibration {
  bool ok = false;
  double yaw = 0.0;       // rad
  double sigma = 0.0;     // rad
  double distance = 0.0;  // m, the move as the laser saw it (|z − z'|)
  std::string message;
};

// From sightings before and after a straight forward move of `distance`
// metres (odometry), which only checks the laser's |z − z'|.
YawCalibration yawFromStraightMove(const FeatureSighting& before, const FeatureSighting& after,
                                   double distance, double distance_tolerance = 0.05);

struct TranslationCalibration {
  bool ok = false;
  Vector2 translation = Vector2::Zero();  // m, the laser in base_link
  Matrix2 covariance = Matrix2::Zero();
  Vector2 feature = Vector2::Zero();  // the feature in the robot frame before the turn
  std::string message;
};

// From sightings before and after a turn on the spot by `turn` radians
// (counter-clockwise positive), with the yaw already known (±yaw_sigma).
TranslationCalibration translationFromTurn(const FeatureSighting& before,
                                           const FeatureSighting& after, double turn, double yaw,
                                           double yaw_sigma);

}  // namespace ekf_slam
