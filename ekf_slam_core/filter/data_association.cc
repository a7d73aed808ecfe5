#include "ekf_slam_core/filter/data_association.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct Pairing {
  int observation;
  int slot;
  double mahalanobis2;
  double normalised;
};

// Joint d² = νᵀ S⁻¹ ν of the pairings observation obs[a] ↔ landmark slot
// slots[a], with `predictions` indexed by slot; +inf when S is not PD.
double jointDistance(const EkfSlam& filter, const std::vector<PointObservation>& observations,
                     const std::vector<EkfSlam::Prediction>& predictions,
                     const std::vector<int>& obs, const std::vector<int>& slots) {
  const int p = static_cast<int>(obs.size());
  if (p == 0) return 0.0;
  const Matrix3 P_rr = filter.poseCovariance();
  Eigen::MatrixXd S(2 * p, 2 * p);
  Eigen::VectorXd nu(2 * p);
  for (int a = 0; a < p; ++a) {
    const int sa = slots[a];
    const EkfSlam::Prediction& pa = predictions[sa];
    const PointObservation& oa = observations[obs[a]];
    nu(2 * a) = oa.z.range - pa.z.range;
    nu(2 * a + 1) = wrapAngle(oa.z.bearing - pa.z.bearing);
    for (int b = 0; b <= a; ++b) {
      const int sb = slots[b];
      const EkfSlam::Prediction& pb = predictions[sb];
      Matrix2 block =
          pa.H_robot * P_rr * pb.H_robot.transpose() +
          pa.H_robot * filter.poseLandmarkCovariance(sb) * pb.H_landmark.transpose() +
          pa.H_landmark * filter.poseLandmarkCovariance(sa).transpose() * pb.H_robot.transpose() +
          pa.H_landmark * filter.landmarkCrossCovariance(sa, sb) * pb.H_landmark.transpose();
      if (a == b) block += oa.covariance;
      S.block<2, 2>(2 * a, 2 * b) = block;
      S.block<2, 2>(2 * b, 2 * a) = block.transpose();
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return kInfinity;
  return llt.matrixL().solve(nu).squaredNorm();
}

// Everything JCBB needs to build joint innovations without recomputing the
// per-landmark predictions.
class JointCompatibility {
 public:
  JointCompatibility(const EkfSlam& filter, const std::vector<PointObservation>& observations,
                     const std::vector<EkfSlam::Prediction>& predictions,
                     const std::vector<std::vector<Pairing>>& compatible, double gate_probability,
                     int max_nodes)
      : filter_(filter),
        observations_(observations),
        predictions_(predictions),
        compatible_(compatible),
        max_nodes_(max_nodes) {
    for (size_t i = 0; i < observations.size(); ++i) order_.push_back(static_cast<int>(i));
    // Few candidates first: prunes the tree early.
    std::stable_sort(order_.begin(), order_.end(),
                     [&](int a, int b) { return compatible_[a].size() < compatible_[b].size(); });
    used_.assign(filter.landmarkCount(), 0);
    // χ²_{2p} gates for p pairings, computed once.
    joint_gate_.push_back(0.0);
    for (size_t p = 1; p <= observations.size(); ++p) {
      joint_gate_.push_back(chiSquareQuantile(gate_probability, 2.0 * p));
    }
    current_.assign(observations.size(), -1);
    best_ = current_;
  }

  std::vector<int> solve(int* nodes) {
    recurse(0, 0);
    *nodes = nodes_;
    return best_;
  }

 private:
  // Joint d² of the pairings in `current_`; +inf when S is not PD.
  double jointDistance() const {
    std::vector<int> obs, slots;
    for (size_t i = 0; i < current_.size(); ++i) {
      if (current_[i] >= 0) {
        obs.push_back(static_cast<int>(i));
        slots.push_back(current_[i]);
      }
    }
    return ekf_slam::jointDistance(filter_, observations_, predictions_, obs, slots);
  }

  void recurse(int depth, int pairings) {
    if (++nodes_ > max_nodes_) return;
    const int n = static_cast<int>(order_.size());
    if (depth == n) {
      const double d2 = jointDistance();
      if (pairings > best_pairings_ || (pairings == best_pairings_ && d2 < best_distance_)) {
        best_ = current_;
        best_pairings_ = pairings;
        best_distance_ = d2;
      }
      return;
    }
    const int i = order_[depth];
    for (const Pairing& candidate : compatible_[i]) {
      if (used_[candidate.slot]) continue;
      current_[i] = candidate.slot;
      const double d2 = jointDistance();
      if (d2 < joint_gate_[pairings + 1]) {
        used_[candidate.slot] = 1;
        recurse(depth + 1, pairings + 1);
        used_[candidate.slot] = 0;
      }
      current_[i] = -1;
      if (nodes_ > max_nodes_) return;
    }
    // Leave observation i unpaired, only if that can still beat the best.
    if (pairings + (n - depth - 1) >= best_pairings_ && best_pairings_ < n) {
      recurse(depth + 1, pairings);
    }
  }

  const EkfSlam& filter_;
  const std::vector<PointObservation>& observations_;
  const std::vector<EkfSlam::Prediction>& predictions_;
  const std::vector<std::vector<Pairing>>& compatible_;
  std::vector<double> joint_gate_;
  const int max_nodes_;
  std::vector<int> order_;
  std::vector<char> used_;
  std::vector<int> current_;  // slot per observation, -1 unpaired
  std::vector<int> best_;
  int best_pairings_ = -1;
  double best_distance_ = kInfinity;
  int nodes_ = 0;
};

}  // namespace

std::string AssociationOptions::validate() const {
  const std::string error = checkFields(*this);
  if (!error.empty()) return error;
  if (new_landmark_probability < gate_probability) {
    return "new_landmark_probability must be >= gate_probability (" +
           std::to_string(gate_probability) + "), got " + std::to_string(new_landmark_probability);
  }
  return "";
}

const char* toString(AssociationDecision decision) {
  switch (decision) {
    case AssociationDecision::kMatched:
      return "matched";
    case AssociationDecision::kNewLandmark:
      return "new";
    case AssociationDecision::kAmbiguous:
      return "ambiguous";
    case AssociationDecision::kInvalid:
      return "invalid";
  }
  return "unknown";
}

std::vector<PointMatch> AssociationResult::matches() const {
  std::vector<PointMatch> out;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (observations[i].decision == AssociationDecision::kMatched) {
      out.push_back({static_cast<int>(i), observations[i].landmark_id});
    }
  }
  return out;
}

std::vector<int> AssociationResult::newLandmarks() const {
  std::vector<int> out;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (observations[i].decision == AssociationDecision::kNewLandmark) {
      out.push_back(static_cast<int>(i));
    }
  }
  return out;
}

LandmarkPredictions::LandmarkPredictions(const EkfSlam& filter)
    : filter_(filter),
      predictions_(filter.landmarkCount()),
      made_(static_cast<size_t>(filter.landmarkCount()), 0) {}

bool LandmarkPredictions::predict(int slot) {
  if (slot < 0 || slot >= static_cast<int>(made_.size())) return false;
  if (made_[slot] == 0)
    made_[slot] = filter_.predictObservation(slot, &predictions_[slot]) ? 1 : -1;
  return made_[slot] > 0;
}

double jointMahalanobis2(const EkfSlam& filter, const std::vector<PointObservation>& observations,
                         const std::vector<PointMatch>& pairings,
                         LandmarkPredictions* predictions) {
  std::vector<int> obs, slots;
  for (const PointMatch& pairing : pairings) {
    const int slot = filter.slotOf(pairing.landmark_id);
    if (pairing.observation < 0 || pairing.observation >= static_cast<int>(observations.size()) ||
        !predictions->predict(slot)) {
      return kInfinity;
    }
    obs.push_back(pairing.observation);
    slots.push_back(slot);
  }
  return jointDistance(filter, observations, predictions->bySlot(), obs, slots);
}

double jointMahalanobis2(const EkfSlam& filter, const std::vector<PointObservation>& observations,
                         const std::vector<PointMatch>& pairings) {
  LandmarkPredictions predictions(filter);
  return jointMahalanobis2(filter, observations, pairings, &predictions);
}

AssociationResult associate(const EkfSlam& filter,
                            const std::vector<PointObservation>& observations,
                            const AssociationOptions& options) {
  AssociationResult result;
  result.gate = chiSquareQuantile(options.gate_probability, 2.0);
  result.new_landmark_gate = chiSquareQuantile(options.new_landmark_probability, 2.0);
  const int m = static_cast<int>(observations.size());
  const int landmarks = filter.landmarkCount();
  result.observations.resize(m);

  std::vector<EkfSlam::Prediction> predictions(landmarks);
  std::vector<char> predicted(landmarks, 0);
  for (int s = 0; s < landmarks; ++s) predicted[s] = filter.predictObservation(s, &predictions[s]);

  // Individual compatibility of every observation with every landmark.
  std::vector<std::vector<Pairing>> compatible(m);
  std::vector<Pairing> all_pairs;
  for (int i = 0; i < m; ++i) {
    const PointObservation& obs = observations[i];
    ObservationAssociation& out = result.observations[i];
    if (!std::isfinite(obs.z.range) || !std::isfinite(obs.z.bearing) ||
        !obs.covariance.allFinite() || !(obs.covariance.determinant() > 0.0)) {
      out.decision = AssociationDecision::kInvalid;
      continue;
    }
    double min_d2 = kInfinity;
    std::vector<Pairing> within_new_gate;
    for (int s = 0; s < landmarks; ++s) {
      if (!predicted[s]) continue;
      const Vector2 nu(obs.z.range - predictions[s].z.range,
                       wrapAngle(obs.z.bearing - predictions[s].z.bearing));
      const Matrix2 S = predictions[s].HPHt + obs.covariance;
      const double det = S.determinant();
      if (!(det > 0.0)) continue;
      // Closed-form 2×2 inverse: νᵀ S⁻¹ ν.
      const double d2 = (S(1, 1) * nu.x() * nu.x() - (S(0, 1) + S(1, 0)) * nu.x() * nu.y() +
                         S(0, 0) * nu.y() * nu.y()) /
                        det;
      min_d2 = std::min(min_d2, d2);
      if (d2 < result.new_landmark_gate) {
        within_new_gate.push_back({i, s, d2, d2 + std::log(det)});
      }
    }
    std::sort(within_new_gate.begin(), within_new_gate.end(),
              [](const Pairing& a, const Pairing& b) { return a.normalised < b.normalised; });
    for (const Pairing& p : within_new_gate) {
      if (static_cast<int>(out.candidates.size()) < options.max_candidates_reported) {
        out.candidates.push_back({filter.landmarks()[p.slot].id, p.mahalanobis2, p.normalised});
      }
      if (p.mahalanobis2 < result.gate) {
        compatible[i].push_back(p);
        all_pairs.push_back(p);
      }
    }
    out.mahalanobis2 = min_d2;
    out.decision = min_d2 > result.new_landmark_gate ? AssociationDecision::kNewLandmark
                                                     : AssociationDecision::kAmbiguous;
  }

  std::vector<int> slot_of_observation(m, -1);
  if (options.method == AssociationMethod::kNearestNeighbour) {
    std::sort(all_pairs.begin(), all_pairs.end(),
              [](const Pairing& a, const Pairing& b) { return a.normalised < b.normalised; });
    std::vector<char> landmark_taken(landmarks, 0);
    for (const Pairing& p : all_pairs) {
      if (slot_of_observation[p.observation] >= 0 || landmark_taken[p.slot]) continue;
      slot_of_observation[p.observation] = p.slot;
      landmark_taken[p.slot] = 1;
    }
  } else {
    JointCompatibility jcbb(filter, observations, predictions, compatible, options.gate_probability,
                            options.jcbb_max_nodes);
    slot_of_observation = jcbb.solve(&result.jcbb_nodes);
  }

  for (int i = 0; i < m; ++i) {
    const int slot = slot_of_observation[i];
    if (slot < 0) continue;
    ObservationAssociation& out = result.observations[i];
    out.decision = AssociationDecision::kMatched;
    out.landmark_id = filter.landmarks()[slot].id;
    for (const Pairing& p : compatible[i]) {
      if (p.slot == slot) out.mahalanobis2 = p.mahalanobis2;
    }
  }
  return result;
}

}  // namespace ekf_slam
