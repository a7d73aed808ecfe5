// Line landmarks for the pipeline (thesis Ch. 4): the extractor's wall
// segments of a scan are gated, associated with the filter's line
// landmarks, used in a line update after the point update, and the unmatched
// ones start landmarks. Two kinds, chosen once per map:
//   kLine       the (p, θ) normal form in the state (§4.3.1);
//   kLineAngle  θ alone in the state, the offset from the point landmarks
//               at the wall's ends when the filter has them (§4.3.3,
//               eqs. 4.35, 4.38).
//
// Association is Mahalanobis-gated nearest neighbour, as for points: a
// segment and a landmark are compatible when the innovation's d² is inside
// the χ²_r gate (r = 1 or 2 rows) of the association's gate_probability,
// candidates are ranked by d² + ln|S|, each landmark takes at most one
// segment per scan, and a segment beyond the new-landmark gate of every
// candidate starts a landmark (in between it is left out). A line is
// infinite, so a segment is a candidate for a landmark only where it
// overlaps the stretch of it seen so far (within overlap_margin): the
// collinear walls of two rooms stay two landmarks.
//
// A θ-only landmark without endpoints says nothing about its offset, so
// that θ alone would match every parallel wall (the two sides of a
// corridor): its association also tests the offset against the latest
// sighting kept here (χ²₁ of the offset difference under both sightings'
// offset variances in the map frame, their correlation neglected, which
// widens the test).
//
// The extent (LineSupport) is kept in the map frame as the two sighted
// points farthest along the line, so that it follows the line's current θ
// and moves with a re-anchoring.
#pragma once

#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/filter/line_support.h"
#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/mecp/doorways.h"

namespace ekf_slam {

// Which features become landmarks.
enum class LandmarkSet {
  kPoints,               // corners and segment ends only (the thesis's §4.2)
  kPointsAndLines,       // + (p, θ) line landmarks
  kPointsAndLineAngles,  // + θ-only line landmarks with endpoint points
  kPointsAndMecp,        // points, each scan's MECP associated as a group (§4.4.3)
};
const char* toString(LandmarkSet set);

struct LineLandmarkOptions {
  // m: shorter segments are not used (furniture, door leaves, clutter);
  // a wall's (p, θ) is only as good as its length.
  double min_length = 1.0;
  // m: segments whose midpoint lies farther from the laser are not used:
  // far away a short θ error is a large offset error and the Gaussian in
  // (p, θ) stops being faithful (LineFeature::linearizationError).
  double max_range = 10.0;
  // m: a segment matches a landmark only if it reaches within this of the
  // stretch of the line seen so far.
  double overlap_margin = 0.5;

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("min_length", min_length, Bounds::atLeast(0.0, "m"));
    v.number("max_range", max_range, Bounds::above(0.0, "m"));
    v.number("overlap_margin", overlap_margin, Bounds::atLeast(0.0, "m"));
  }
};

// What happened to the lines of one scan.
struct LineIterationReport {
  std::vector<LineObservation> observations;  // the segments offered, laser frame
  std::vector<int> observation_line;          // per observation: its index in FeatureSet::lines
  std::vector<LineMatch> matches;             // those used in the update
  std::vector<double> nis;                    // per match
  std::vector<int> new_landmark_ids;
  int refused = 0;    // segments with a non-finite value or covariance
  int ambiguous = 0;  // between the gates, or lost the landmark to a better segment
  int augment_failures = 0;
  int endpoint_matches = 0;  // θ-only matches whose offset came from endpoint points
  FilterStatus update_status = FilterStatus::kOk;
};

class LineLandmarks {
 public:
  // `kind` is kLine or kLineAngle.
  LineLandmarks(LandmarkKind kind, const LineLandmarkOptions& options,
                const AssociationOptions& association);

  // The lines of one scan, after its point observation `points` (whose
  // matched and created landmarks give a θ-only line its endpoints).
  // `observation_feature` maps each point observation to its index in
  // features.points_of_interest.
  void observe(EkfSlam& filter, const FeatureSet& features,
               const std::vector<int>& observation_feature, const IterationReport& points,
               LineIterationReport* out);

  // After landmarks were removed or merged outside observe() (pruning,
  // the landmark bound): entries of landmarks no longer in the filter go,
  // endpoint ids follow merges or are cleared.
  void synchronise(const EkfSlam& filter);

  // The filter was re-anchored (EkfSlam::reanchor): the kept sightings of
  // the listed landmarks move with them.
  void reanchor(const std::vector<std::pair<int, Pose2>>& corrections);

  // Line landmarks seeded from a map file (seedFilter): their extents and
  // endpoint ids as the file gives them. A (p, θ) line's track spans its
  // extent; a θ-only line's spans its endpoint points (with none it gets
  // no track and matches through θ alone until it is seen again).
  void seed(const EkfSlam& filter, const std::unordered_map<int, LineSupport>& support);

  // Per line landmark id, its seen extent along the current estimate.
  const std::unordered_map<int, LineSupport>& support() const { return support_; }

  // The walls mapped so far: per line landmark in the filter (by id), the
  // stretch of it sighted, map frame, from its two extreme sighted points.
  std::vector<Segment2> walls(const EkfSlam& filter) const;

 private:
  struct Track {
    Vector2 first = Vector2::Zero();       // sighted points, map frame: the least …
    Vector2 last = Vector2::Zero();        // … and the farthest along the line
    Vector2 latest_mid = Vector2::Zero();  // midpoint of the latest sighting, map frame
    double latest_offset_variance = 0.0;   // m², of that sighting's offset in the map frame
    int endpoint_ids[2] = {-1, -1};
  };
  struct Segment {
    Vector2 a, b;  // map frame
  };
  struct Candidate {
    int observation = -1;
    int landmark_id = -1;
    LineMatch match;
    double mahalanobis2 = 0.0;
    double score = 0.0;  // d² + ln|S|
  };
  struct Gates {  // χ² quantiles: association (1 and 2 rows), new landmark
    double one = 0.0, two = 0.0, new_one = 0.0, new_two = 0.0;
  };

  // The steps of observe().
  static std::unordered_map<int, int> pointLandmarksByFeature(
      const IterationReport& points, const std::vector<int>& observation_feature);
  std::vector<Segment> gateSegments(const EkfSlam& filter, const FeatureSet& features,
                                    LineIterationReport* report) const;
  std::vector<Candidate> candidatesOf(const EkfSlam& filter, const std::vector<Segment>& segments,
                                      const LineIterationReport& report,
                                      std::vector<char>* near_new_gate) const;
  bool candidate(const EkfSlam& filter, int observation, int slot, const Track& track,
                 const LineObservation& obs, const Gates& gates, Candidate* out,
                 bool* near_new) const;
  void segmentEnds(const FeatureSet& features, int line,
                   const std::unordered_map<int, int>& landmark_of_feature, int ends[2]) const;
  void addEndpoints(const EkfSlam& filter, int id, const int ends[2]);

  Segment toMap(const EkfSlam& filter, const LineFeature& line) const;
  double landmarkTheta(const EkfSlam& filter, int slot) const;
  bool overlaps(const EkfSlam& filter, int slot, const Track& track, const Segment& s) const;
  // Offset test of a θ-only landmark without endpoints; false when it fails.
  bool offsetCompatible(const EkfSlam& filter, int slot, const Track& track,
                        const LineObservation& observation, double* d2) const;
  double offsetVariance(const EkfSlam& filter, const LineObservation& observation) const;
  void remember(const EkfSlam& filter, int id, const LineObservation& observation,
                const Segment& segment, bool extend);
  void refreshSupport(const EkfSlam& filter);
  // Endpoint ids follow the point merges `merged` ((kept, dropped) pairs,
  // in order); those of landmarks no longer in the filter are cleared.
  void followEndpoints(const EkfSlam& filter, const std::vector<std::pair<int, int>>& merged);

  LandmarkKind kind_;
  LineLandmarkOptions options_;
  AssociationOptions association_;
  std::unordered_map<int, Track> tracks_;
  std::unordered_map<int, LineSupport> support_;
};

}  // namespace ekf_slam
