// The MECP as an extra filter update (thesis §4.4.3–4.4.4): from one scan's
// point readings that are already matched to (or were just made into)
// point landmarks, the maximum empty convex polygon around the robot; its
// centre, observed as the mean of the members' readings (observeMecp) and
// predicted as the mean of the member landmarks (predictMecpObservation),
// updates the filter through EkfSlam::updateGeneric. The MECP is not added
// to the state; its member ids are what associates it (§4.4.4).
//
// Information is reused: the members' readings also update the filter as
// points in the same scan, and the filter does not know the two are
// correlated, so an MECP update after the point updates makes the filter
// overconfident. The thesis does this; docs/results.md measures the cost.
//
// Skipped (nothing changes) when no polygon with at least three matched
// vertices contains the robot, or when the centre is so close to the
// laser that the bearing's linearisation fails: the predicted bearing's
// standard deviation sqrt(S_φφ) above max_bearing_sigma (S = H P Hᵀ + R),
// i.e. the centre's distance ρ below 1 / max_bearing_sigma times its
// across-range standard deviation.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/geometry/option_fields.h"

namespace ekf_slam {

struct MecpUpdateOptions {
  // rad: sqrt(S_φφ) beyond this skips the update (0.2: ρ >= 5σ).
  double max_bearing_sigma = 0.2;

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("max_bearing_sigma", max_bearing_sigma, Bounds::openClosed(0.0, kPi, "rad"));
  }
  std::string validate() const { return checkFields(*this); }  // empty when valid
};

enum class MecpOutcome {
  kApplied,       // the filter was updated
  kNoPolygon,     // fewer than three matched readings, or none encloses the robot
  kNearCentre,    // centre too close to the laser (max_bearing_sigma)
  kFilterRefused  // updateGeneric refused (status says why)
};

struct MecpUpdateResult {
  MecpOutcome outcome = MecpOutcome::kNoPolygon;
  FilterStatus status = FilterStatus::kOk;  // of updateGeneric, when called
  std::vector<int> member_ids;              // the polygon's landmarks, counter-clockwise
  double nis = 0.0;                         // νᵀ S⁻¹ ν when applied
};

// `observations` are one scan's point readings (laser frame); `landmark_ids`
// holds, per reading, the point landmark it was matched to or created as
// (−1: neither; such readings take no part). The polygon contains the
// robot's origin (base_link), found among the matched readings in the laser
// frame.
MecpUpdateResult updateWithMecp(EkfSlam* filter, const std::vector<PointObservation>& observations,
                                const std::vector<int>& landmark_ids,
                                const MecpUpdateOptions& options = {});

}  // namespace ekf_slam
