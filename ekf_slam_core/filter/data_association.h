// Data association of point observations to map landmarks (thesis §4.2.3),
// explainable: every decision carries its candidates and distances.
//
// Individual compatibility: dᵢⱼ² = νᵢⱼᵀ Sᵢⱼ⁻¹ νᵢⱼ < gate = χ²₂(gate_probability).
// Nearest neighbour ranks candidates by the normalised distance
// dᵢⱼ² + ln|Sᵢⱼ| (which, unlike d² alone, does not favour landmarks that are
// merely uncertain) and assigns greedily, each landmark at most once per scan.
// Joint Compatibility Branch and Bound (Neira & Tardós 2001) instead searches
// for the largest set of pairings whose stacked innovation passes the joint
// gate χ²_{2p}, breaking ties by the joint distance.
// An observation with no candidate inside the gate becomes a new landmark
// only when its smallest d² exceeds the larger new-landmark gate; in between
// it is left out (neither matched nor added), which avoids duplicates.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/filter/ekf_slam.h"

#include "ekf_slam_core/geometry/option_fields.h"

namespace ekf_slam {

enum class AssociationMethod { kNearestNeighbour, kJointCompatibility };

struct AssociationOptions {
  AssociationMethod method = AssociationMethod::kNearestNeighbour;
  double gate_probability = 0.99;             // association gate, χ²₂ quantile
  double new_landmark_probability = 0.99999;  // beyond this gate: new landmark
  int jcbb_max_nodes = 20000;                 // search budget; best so far when exhausted
  int max_candidates_reported = 5;            // per observation, for the report
  // Duplicate landmarks: after each update, a landmark that was matched or
  // created is merged with any other within merge_distance (m) whose
  // difference the joint covariance puts at zero with this probability
  // (χ²₂ quantile of the squared Mahalanobis distance). A corner re-seen
  // with a drifted pose outside the new-landmark gate becomes a second
  // landmark; after the loop closes the two converge and are merged. 0: off.
  double merge_probability = 0.95;
  double merge_distance = 0.5;
  // m: how far two extractions of one corner may disagree beyond their noise
  // model (a corner vs a segment end of the same box, a rasterised corner
  // seen from two sides); added as b²I to the merge test and update.
  double merge_bias_sigma = 0.02;

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.choice("method", method,
             {{AssociationMethod::kNearestNeighbour, "nn"},
              {AssociationMethod::kJointCompatibility, "jcbb"}});
    v.number("gate_probability", gate_probability, Bounds::open(0.0, 1.0));
    v.number("new_landmark_probability", new_landmark_probability, Bounds::open(0.0, 1.0));
    v.number("merge_probability", merge_probability, Bounds::closedOpen(0.0, 1.0));
    v.number("merge_distance", merge_distance, Bounds::closed(0.0, 1e3, "m"));
    v.number("merge_bias_sigma", merge_bias_sigma, Bounds::closed(0.0, 1.0, "m"));
    v.integer("jcbb_max_nodes", jcbb_max_nodes, Bounds::closed(1, 1e8, "nodes"));
    v.integer("max_candidates_reported", max_candidates_reported, Bounds::closed(0, 1000));
  }

  // Empty when valid, else names the bad field. Beyond each field's bounds:
  // new_landmark_probability >= gate_probability.
  std::string validate() const;
};

struct AssociationCandidate {
  int landmark_id = -1;
  double mahalanobis2 = 0.0;  // d² = νᵀ S⁻¹ ν
  double normalised = 0.0;    // d² + ln|S|
};

enum class AssociationDecision {
  kMatched,      // paired with landmark_id
  kNewLandmark,  // outside the new-landmark gate of every landmark
  kAmbiguous,    // between the gates, or lost the landmark to a better observation
  kInvalid,      // non-finite observation or covariance
};

const char* toString(AssociationDecision decision);

struct ObservationAssociation {
  AssociationDecision decision = AssociationDecision::kInvalid;
  int landmark_id = -1;                          // when matched
  double mahalanobis2 = 0.0;                     // of the match, or smallest d² otherwise
  std::vector<AssociationCandidate> candidates;  // best first, within the new-landmark gate
};

struct AssociationResult {
  std::vector<ObservationAssociation> observations;  // one per input observation
  double gate = 0.0;                                 // χ² threshold used for matching
  double new_landmark_gate = 0.0;
  int jcbb_nodes = 0;  // nodes expanded by JCBB (0 for NN)

  std::vector<PointMatch> matches() const;
  std::vector<int> newLandmarks() const;  // observation indices
};

// The joint squared Mahalanobis distance νᵀ S⁻¹ ν of several pairings at
// once (the stacked innovation and its full covariance, as JCBB tests
// them); +inf when a pairing names a missing observation or landmark, a
// landmark cannot be predicted, or S is not positive definite. 0 for none.
double jointMahalanobis2(const EkfSlam& filter, const std::vector<PointObservation>& observations,
                         const std::vector<PointMatch>& pairings);

// The landmarks' predicted observations for one filter state, each made
// the first time it is asked for: many pairings tested in turn (a group's
// cyclic shifts) then predict each landmark once.
class LandmarkPredictions {
 public:
  explicit LandmarkPredictions(const EkfSlam& filter);
  // False when landmark `slot` cannot be predicted (or does not exist).
  bool predict(int slot);
  const std::vector<EkfSlam::Prediction>& bySlot() const { return predictions_; }

 private:
  const EkfSlam& filter_;
  std::vector<EkfSlam::Prediction> predictions_;
  std::vector<signed char> made_;  // 0 not yet, 1 made, −1 impossible
};

// jointMahalanobis2 with the predictions of `predictions` (the same filter).
double jointMahalanobis2(const EkfSlam& filter, const std::vector<PointObservation>& observations,
                         const std::vector<PointMatch>& pairings, LandmarkPredictions* predictions);

AssociationResult associate(const EkfSlam& filter,
                            const std::vector<PointObservation>& observations,
                            const AssociationOptions& options);

}  // namespace ekf_slam
