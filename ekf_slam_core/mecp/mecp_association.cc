#include "ekf_slam_core/mecp/mecp_association.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_core/mecp/empty_convex_polygon.h"
#include "ekf_slam_core/mecp/mecp_observation.h"

namespace ekf_slam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct Candidate {
  int polygon = -1;
  double mahalanobis2 = 0.0;
  double normalised = 0.0;  // d² + ln|S|
};

// rad²: a centre bearing's predicted variance beyond this (σ 0.2 rad: the
// centre nearer the laser than five times its across-range uncertainty)
// is not linear enough to gate on.
constexpr double kMaxBearingVariance = 0.2 * 0.2;

// The centre's d² of the scan's polygon against the remembered `members`,
// the gate it is compared with (χ²₂, or χ²₁ when only the range counts)
// and ln|S|; false when a member is missing or the prediction fails.
bool centreDistance(const EkfSlam& filter, const std::vector<int>& members,
                    const RangeBearing& observed, const Matrix2& noise, double full_gate,
                    double range_gate, double* d2, double* gate, double* log_det) {
  std::vector<int> slots;
  std::vector<Vector2> positions;
  for (int id : members) {
    const int slot = filter.slotOf(id);
    if (slot < 0 || filter.landmarks()[slot].kind != LandmarkKind::kPoint) return false;
    slots.push_back(slot);
    positions.push_back(filter.landmarkPosition(slot));
  }
  RangeBearing predicted;
  Matrix23 H_robot;
  std::vector<Matrix2> H_members;
  if (!predictMecpObservation(filter.pose(), filter.options().laser_pose, positions, &predicted,
                              &H_robot, &H_members)) {
    return false;
  }
  const int k = static_cast<int>(slots.size());
  Matrix2 S = H_robot * filter.poseCovariance() * H_robot.transpose() + noise;
  for (int i = 0; i < k; ++i) {
    const Matrix2 cross =
        H_robot * filter.poseLandmarkCovariance(slots[i]) * H_members[i].transpose();
    S += cross + cross.transpose();
    for (int j = 0; j < k; ++j) {
      const Matrix2 P_ij = i == j ? filter.landmarkCovariance(slots[i])
                                  : filter.landmarkCrossCovariance(slots[i], slots[j]);
      S += H_members[i] * P_ij * H_members[j].transpose();
    }
  }
  const Vector2 nu(observed.range - predicted.range,
                   wrapAngle(observed.bearing - predicted.bearing));
  if (S(1, 1) > kMaxBearingVariance) {
    // The centre lies too near the laser for its bearing to be linear in
    // the state: the range alone is gated.
    if (!(S(0, 0) > 0.0)) return false;
    *d2 = nu.x() * nu.x() / S(0, 0);
    *gate = range_gate;
    *log_det = std::log(S(0, 0));
  } else {
    const double det = S.determinant();
    if (!(det > 0.0)) return false;
    *d2 = nu.dot(S.inverse() * nu);
    *gate = full_gate;
    *log_det = std::log(det);
  }
  return std::isfinite(*d2);
}

}  // namespace

std::vector<int> observedPolygon(const std::vector<PointObservation>& observations,
                                 const Pose2& laser) {
  std::vector<Vector2> points;
  std::vector<int> observation_of_point;
  for (size_t i = 0; i < observations.size(); ++i) {
    const RangeBearing& z = observations[i].z;
    if (!std::isfinite(z.range) || !std::isfinite(z.bearing)) continue;
    points.emplace_back(z.range * std::cos(z.bearing), z.range * std::sin(z.bearing));
    observation_of_point.push_back(static_cast<int>(i));
  }
  std::vector<int> polygon = maximumEmptyConvexPolygon(points, inverse(laser).translation());
  for (int& v : polygon) v = observation_of_point[v];
  return polygon;
}

AssociationResult MecpAssociation::associate(const EkfSlam& filter,
                                             const std::vector<PointObservation>& observations,
                                             const AssociationOptions& association,
                                             const Associator& base) {
  AssociationResult result = base ? base(filter, observations, association)
                                  : ekf_slam::associate(filter, observations, association);
  last_ = MecpScanMatch();
  last_.vertices = observedPolygon(observations, filter.options().laser_pose);
  const int k = static_cast<int>(last_.vertices.size());
  if (k < 3) {
    last_.vertices.clear();
    return result;
  }
  ++counters_.mecp_polygons;

  std::vector<RangeBearing> readings;
  std::vector<Matrix2> reading_covariances;
  for (int v : last_.vertices) {
    readings.push_back(observations[v].z);
    reading_covariances.push_back(observations[v].covariance);
  }
  RangeBearing observed;
  Matrix2 noise;
  if (!observeMecp(readings, reading_covariances, &observed, &noise)) return result;

  const double centre_gate = chiSquareQuantile(association.gate_probability, 2.0);
  const double range_gate = chiSquareQuantile(association.gate_probability, 1.0);
  std::vector<Candidate> candidates;
  for (int p = 0; p < static_cast<int>(polygons_.size()); ++p) {
    if (static_cast<int>(polygons_[p].size()) != k) continue;
    Candidate candidate{p, 0.0, 0.0};
    double log_det = 0.0, gate = 0.0;
    if (!centreDistance(filter, polygons_[p], observed, noise, centre_gate, range_gate,
                        &candidate.mahalanobis2, &gate, &log_det) ||
        !(candidate.mahalanobis2 < gate)) {
      continue;
    }
    candidate.normalised = candidate.mahalanobis2 + log_det;
    candidates.push_back(candidate);
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.normalised < b.normalised; });

  // Each member's prediction made once for every shift and candidate.
  LandmarkPredictions predictions(filter);
  const double group_gate = chiSquareQuantile(association.gate_probability, 2.0 * k);
  const double single_gate = chiSquareQuantile(association.gate_probability, 2.0);
  for (const Candidate& candidate : candidates) {
    const std::vector<int>& members = polygons_[candidate.polygon];
    double best = kInfinity;
    std::vector<PointMatch> best_pairing;
    for (int shift = 0; shift < k; ++shift) {
      std::vector<PointMatch> pairing;
      bool each_compatible = true;
      for (int i = 0; i < k && each_compatible; ++i) {
        pairing.push_back({last_.vertices[i], members[(i + shift) % k]});
        each_compatible =
            jointMahalanobis2(filter, observations, {pairing.back()}, &predictions) < single_gate;
      }
      if (!each_compatible) continue;
      const double d2 = jointMahalanobis2(filter, observations, pairing, &predictions);
      if (d2 < best) {
        best = d2;
        best_pairing = pairing;
      }
    }
    if (!(best < group_gate)) {
      ++counters_.mecp_group_refused;
      continue;
    }
    // The group's pairings replace whatever the point association said.
    std::vector<int> before;
    for (const PointMatch& pair : best_pairing) {
      const ObservationAssociation& out = result.observations[pair.observation];
      before.push_back(out.decision == AssociationDecision::kMatched ? out.landmark_id : -1);
    }
    for (ObservationAssociation& other : result.observations) {
      if (other.decision != AssociationDecision::kMatched) continue;
      for (const PointMatch& pair : best_pairing) {
        if (other.landmark_id == pair.landmark_id) {
          other.decision = AssociationDecision::kAmbiguous;
          other.landmark_id = -1;
        }
      }
    }
    for (int i = 0; i < k; ++i) {
      const PointMatch& pair = best_pairing[i];
      ObservationAssociation& out = result.observations[pair.observation];
      if (before[i] != pair.landmark_id) ++counters_.mecp_pairings_changed;
      out.decision = AssociationDecision::kMatched;
      out.landmark_id = pair.landmark_id;
      out.mahalanobis2 = jointMahalanobis2(filter, observations, {pair}, &predictions);
    }
    ++counters_.mecp_group_matches;
    last_.member_ids = members;
    last_.centre_mahalanobis2 = candidate.mahalanobis2;
    last_.group_mahalanobis2 = best;
    break;
  }
  return result;
}

void MecpAssociation::remember(const EkfSlam& filter, const IterationReport& report) {
  if (last_.vertices.empty() || !last_.member_ids.empty()) return;
  std::vector<int> ids;
  for (int v : last_.vertices) {
    int id = -1;
    for (const PointMatch& m : report.matches) {
      if (m.observation == v) id = m.landmark_id;
    }
    for (const PointMatch& m : report.created) {
      if (m.observation == v) id = m.landmark_id;
    }
    for (const auto& [kept, dropped] : report.merged) {
      if (id == dropped) id = kept;
    }
    if (id < 0 || filter.slotOf(id) < 0) return;
    ids.push_back(id);
  }
  std::vector<int> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return;
  for (const std::vector<int>& known : polygons_) {
    std::vector<int> known_sorted = known;
    std::sort(known_sorted.begin(), known_sorted.end());
    if (known_sorted == sorted) return;
  }
  // Forget polygons whose members left the map, then the oldest beyond the bound.
  polygons_.erase(std::remove_if(polygons_.begin(), polygons_.end(),
                                 [&](const std::vector<int>& members) {
                                   return std::any_of(members.begin(), members.end(), [&](int id) {
                                     return filter.slotOf(id) < 0;
                                   });
                                 }),
                  polygons_.end());
  polygons_.push_back(ids);
  if (static_cast<int>(polygons_.size()) > kMaxPolygons) polygons_.erase(polygons_.begin());
  ++counters_.mecp_remembered;
}

}  // namespace ekf_slam
