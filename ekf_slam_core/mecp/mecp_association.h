// MECP association (thesis §4.4.3–4.4.4): whole regions associated at once.
//
// Each scan's point observations that enclose the robot give its maximum
// empty convex polygon (empty_convex_polygon.h). Once every vertex of a
// scan's polygon is a landmark of the state (matched or just created), the
// polygon is remembered as the list of its member landmarks' ids,
// counter-clockwise (§4.4.4: an index list, not a state element).
//
// A later scan's polygon is matched against the remembered ones:
//   1. centre gate: the polygon's centre, observed as the mean of its
//      vertices' readings with covariance T R Tᵀ (observeMecp) and
//      predicted as the mean of a remembered polygon's member landmarks
//      (predictMecpObservation), gives d² = νᵀ S⁻¹ ν with
//      S = H P Hᵀ + T R Tᵀ over the pose and every member; remembered
//      polygons with as many vertices and d² inside the point association's
//      χ²₂(gate_probability) are candidates, best d² + ln|S| first;
//   2. group gate: both polygons are counter-clockwise, so the vertices
//      pair up by one of k cyclic shifts; of the shifts whose every pairing
//      is individually compatible (d² inside χ²₂, as JCBB's candidates),
//      the one with the smallest joint d² of its k pairings
//      (jointMahalanobis2: the stacked innovation and its full covariance)
//      is kept when that d² lies inside χ²_2k(gate_probability).
// The first candidate that passes both gates associates its members as a
// group: each vertex observation is paired with its member, whatever the
// point association said of it, and any other observation the point
// association gave one of those members is left out (ambiguous). The
// observations outside the polygon keep the point association's decision
// (nearest neighbour, JCBB or room-gated: the `base` associator).
//
// Where this wins over nearest neighbour: after a long loop the pose is
// uncertain enough that a corner's individual gate holds several
// landmarks, and the one nearest in d² + ln|S| can be the wrong one; the
// polygon's vertices must all fit one pose error together and in their
// order round the robot, which a wrong neighbour rarely does.
//
// The polygon's readings update the filter once, as the points they are
// (no separate centre update: that would use the same readings twice).
#pragma once

#include <vector>

#include "ekf_slam_core/filter/slam_iteration.h"

namespace ekf_slam {

struct MecpCounters {
  long mecp_polygons = 0;       // scans whose observations enclosed the robot in a polygon
  long mecp_group_matches = 0;  // … matched to a remembered polygon, members paired as a group
  long mecp_group_refused = 0;  // … whose centre fitted a remembered polygon but no pairing did
  long mecp_pairings_changed = 0;  // vertex pairings the group set differently from the points
  long mecp_remembered = 0;        // polygons added to the remembered list
};

// What the last associate() found, for the caller's report.
struct MecpScanMatch {
  std::vector<int> vertices;    // observation indices, counter-clockwise; empty: no polygon
  std::vector<int> member_ids;  // the remembered polygon's landmarks paired with them; empty: none
  double centre_mahalanobis2 = 0.0;
  double group_mahalanobis2 = 0.0;
};

class MecpAssociation {
 public:
  // Remembered polygons beyond this bound: the oldest is forgotten.
  static constexpr int kMaxPolygons = 2000;

  // The association of one scan: `base` (associate() when null) for every
  // observation, then the scan's polygon matched and its members paired as
  // a group (see above).
  AssociationResult associate(const EkfSlam& filter,
                              const std::vector<PointObservation>& observations,
                              const AssociationOptions& association, const Associator& base);
  // After the scan's update and augmentation (`report` of observe()):
  // remembers the scan's polygon when it matched none and every vertex is
  // now a landmark.
  void remember(const EkfSlam& filter, const IterationReport& report);

  const MecpScanMatch& lastScan() const { return last_; }
  // The remembered polygons, each its members' ids counter-clockwise.
  const std::vector<std::vector<int>>& polygons() const { return polygons_; }
  const MecpCounters& counters() const { return counters_; }

 private:
  std::vector<std::vector<int>> polygons_;
  MecpScanMatch last_;
  MecpCounters counters_;
};

// The maximum empty convex polygon of `observations` (laser frame) around
// the robot's origin, whose laser is mounted at `laser`: observation
// indices counter-clockwise; empty when none encloses it.
std::vector<int> observedPolygon(const std::vector<PointObservation>& observations,
                                 const Pose2& laser);

}  // namespace ekf_slam
