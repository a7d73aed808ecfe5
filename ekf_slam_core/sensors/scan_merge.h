// Two planar scans, each from its own laser on the robot (e.g. a front and a
// rear LMS200), as one 360° scan seen from a virtual laser at the base_link
// origin: what the pipeline needs for features on every side of the robot
// (the MECP of thesis §4.4).
//
// Every valid reading (Scan::isValid) of either scan becomes a point in
// base_link through its laser's mount; the points of the second scan are
// moved by the robot's motion between the two stamps into the first scan's
// base_link. Each point is then a (range, bearing) about the origin, and
// falls into the beam whose bearing is nearest; a beam keeps the nearest of
// its points (a nearer surface hides a farther one, as it would for a laser
// at the origin). A beam with no point is +inf, "no return".
//
// The merged scan: angle_min −π, n = round(2π / angle_increment) beams
// spaced exactly 2π / n (so the sweep closes on itself), range_min 0,
// range_max beyond the farthest valid reading either laser can give from
// the origin (each laser's range_max plus its distance from the origin, the
// motion's included for the second), stamp = the first scan's stamp.
//
// What a laser at the origin would see and the merge does not: a laser
// mounted away from the origin does not see the points beside it at right
// angles from the origin's view, so a front and a rear laser on the robot's
// axis leave a wedge on each side unseen (about 12° at 2 m for the P3-DX's
// mounts 0.16 m ahead of and 0.25 m behind the axle); and a surface seen by
// one laser past the edge of a nearer object (parallax) can fill a beam the
// origin would not see it in. A beam holds its reading's true distance; its
// bearing is quantised to the beam (at most half an increment off, which
// the feature extraction counts as noise of variance increment² / 12), and
// an object's end beside an occlusion edge cannot be placed (Scan::merged).
#pragma once

#include <string>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

struct ScanMergeOptions {
  // rad, bearing step of the merged scan; rounded so that 2π holds a whole
  // number of beams. Bounds: [1e-4, π/4].
  double angle_increment = degToRad(0.5);
};

// The scan as the merge sees it: its readings and where its laser sits in
// base_link (the static transform base_link -> the scan's frame).
struct MountedScan {
  const Scan* scan = nullptr;
  Pose2 mount;
};

// Merges `first` and `second` into `merged` (see above). `second_motion` is
// base_link at the second scan's stamp expressed in base_link at the first
// scan's stamp (odom→base(t1)⁻¹ ∘ odom→base(t2)); the identity when the two
// were taken together or the robot stood still. An empty second scan (no
// beams) adds nothing, whatever its geometry.
//
// Returns "" on success. Otherwise `merged` is left unchanged and the message
// names the problem: a scan with beams whose geometry validateScan refuses
// ("second scan: Scan.angle_min must be finite, got nan"), a non-finite mount
// or motion, or an angle_increment out of bounds. Invalid readings (NaN,
// ±inf, outside [range_min, range_max)) are no error: they are skipped, and
// the merged scan holds only finite ranges and +inf.
std::string mergeScans(const MountedScan& first, const MountedScan& second,
                       const Pose2& second_motion, const ScanMergeOptions& options, Scan* merged);

}  // namespace ekf_slam
