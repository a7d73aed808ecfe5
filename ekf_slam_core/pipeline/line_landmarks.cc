#include "ekf_slam_core/pipeline/line_landmarks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {

const char* toString(LandmarkSet set) {
  switch (set) {
    case LandmarkSet::kPoints:
      return "points";
    case LandmarkSet::kPointsAndLines:
      return "points+lines";
    case LandmarkSet::kPointsAndLineAngles:
      return "points+lines_theta";
    case LandmarkSet::kPointsAndMecp:
      return "points+mecp";
  }
  return "unknown";
}

namespace {

Vector2 direction(double theta) { return Vector2(-std::sin(theta), std::cos(theta)); }

bool finiteLine(const LineFeature& line) {
  return std::isfinite(line.p) && std::isfinite(line.theta) && line.covariance.allFinite() &&
         line.start.allFinite() && line.end.allFinite();
}

}  // namespace

LineLandmarks::LineLandmarks(LandmarkKind kind, const LineLandmarkOptions& options,
                             const AssociationOptions& association)
    : kind_(kind), options_(options), association_(association) {}

LineLandmarks::Segment LineLandmarks::toMap(const EkfSlam& filter, const LineFeature& line) const {
  const Pose2 sensor = compose(filter.pose(), filter.options().laser_pose);
  return {transformFrom(sensor, line.start), transformFrom(sensor, line.end)};
}

double LineLandmarks::landmarkTheta(const EkfSlam& filter, int slot) const {
  return filter.landmarkKind(slot) == LandmarkKind::kLine ? filter.lineLandmark(slot).theta
                                                          : filter.lineAngle(slot);
}

bool LineLandmarks::overlaps(const EkfSlam& filter, int slot, const Track& track,
                             const Segment& s) const {
  const Vector2 d = direction(landmarkTheta(filter, slot));
  const double seen_a = d.dot(track.first), seen_b = d.dot(track.last);
  const double seg_a = d.dot(s.a), seg_b = d.dot(s.b);
  return std::max(seg_a, seg_b) >= std::min(seen_a, seen_b) - options_.overlap_margin &&
         std::min(seg_a, seg_b) <= std::max(seen_a, seen_b) + options_.overlap_margin;
}

double LineLandmarks::offsetVariance(const EkfSlam& filter,
                                     const LineObservation& observation) const {
  PolarLine line;
  Matrix23 G_robot;
  Matrix2 G_z, covariance;
  if (!lineLandmarkFromObservation(filter.pose(), filter.options().laser_pose, observation.z, &line,
                                   &G_robot, &G_z) ||
      !newLineLandmarkCovariance(filter.poseCovariance(), observation.covariance, G_robot, G_z,
                                 &covariance)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return covariance(0, 0);
}

bool LineLandmarks::offsetCompatible(const EkfSlam& filter, int slot, const Track& track,
                                     const LineObservation& observation, double* d2) const {
  PolarLine seen;
  if (!lineLandmarkFromObservation(filter.pose(), filter.options().laser_pose, observation.z,
                                   &seen)) {
    return false;
  }
  const double theta = filter.lineAngle(slot);
  const Vector2 normal(std::cos(theta), std::sin(theta));
  // The sighting's offset along the landmark's normal (its normal may point
  // the other way: θ-only landmarks are compared modulo π).
  const double offset = std::cos(seen.theta - theta) >= 0.0 ? seen.p : -seen.p;
  const double variance = offsetVariance(filter, observation) + track.latest_offset_variance;
  if (!(variance > 0.0) || !std::isfinite(variance)) return false;
  const double difference = offset - normal.dot(track.latest_mid);
  *d2 = difference * difference / variance;
  return *d2 <= chiSquareQuantile(association_.new_landmark_probability, 1.0);
}

void LineLandmarks::remember(const EkfSlam& filter, int id, const LineObservation& observation,
                             const Segment& segment, bool extend) {
  Track& track = tracks_[id];
  if (!extend) {
    track.first = segment.a;
    track.last = segment.b;
  } else {
    const int slot = filter.slotOf(id);
    const Vector2 d = direction(landmarkTheta(filter, slot));
    Vector2 lo = track.first, hi = track.last;
    if (d.dot(lo) > d.dot(hi)) std::swap(lo, hi);
    for (const Vector2& q : {segment.a, segment.b}) {
      if (d.dot(q) < d.dot(lo)) lo = q;
      if (d.dot(q) > d.dot(hi)) hi = q;
    }
    track.first = lo;
    track.last = hi;
  }
  track.latest_mid = 0.5 * (segment.a + segment.b);
  track.latest_offset_variance = offsetVariance(filter, observation);
}

void LineLandmarks::observe(EkfSlam& filter, const FeatureSet& features,
                            const std::vector<int>& observation_feature,
                            const IterationReport& points, LineIterationReport* out) {
  LineIterationReport& report = *out;
  // The point step of this scan merged and pruned point landmarks.
  followEndpoints(filter, points.merged);
  const std::unordered_map<int, int> landmark_of_feature =
      pointLandmarksByFeature(points, observation_feature);
  const std::vector<Segment> segments = gateSegments(filter, features, &report);
  const int count = static_cast<int>(report.observations.size());
  std::vector<char> near_new_gate(count, 0);
  std::vector<Candidate> candidates = candidatesOf(filter, segments, report, &near_new_gate);

  // Greedy nearest neighbour: best pairs first, one per segment and landmark.
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
  std::vector<char> taken(count, 0);
  std::unordered_map<int, char> landmark_taken;
  for (const Candidate& c : candidates) {
    if (taken[c.observation] || landmark_taken[c.landmark_id]) continue;
    taken[c.observation] = 1;
    landmark_taken[c.landmark_id] = 1;
    report.matches.push_back(c.match);
  }

  report.update_status = filter.updateLines(report.observations, report.matches, &report.nis);
  if (report.update_status != FilterStatus::kOk) {
    report.matches.clear();
    report.nis.clear();
  }
  for (const LineMatch& m : report.matches) {
    report.endpoint_matches += m.endpoint_ids[0] >= 0 || m.endpoint_ids[1] >= 0;
  }
  for (const LineMatch& m : report.matches) {
    remember(filter, m.landmark_id, report.observations[m.observation],
             toMap(filter, features.lines[report.observation_line[m.observation]]), true);
    if (kind_ == LandmarkKind::kLineAngle) {
      int ends[2];
      segmentEnds(features, report.observation_line[m.observation], landmark_of_feature, ends);
      addEndpoints(filter, m.landmark_id, ends);
    }
  }
  // Augment after the update so new landmarks hang off the corrected pose.
  for (int i = 0; i < count; ++i) {
    if (taken[i]) continue;
    if (near_new_gate[i]) {
      ++report.ambiguous;
      continue;
    }
    int id = -1;
    if (filter.augmentLine(report.observations[i], kind_, &id) != FilterStatus::kOk) {
      ++report.augment_failures;
      continue;
    }
    report.new_landmark_ids.push_back(id);
    remember(filter, id, report.observations[i],
             toMap(filter, features.lines[report.observation_line[i]]), false);
    if (kind_ == LandmarkKind::kLineAngle) {
      int ends[2];
      segmentEnds(features, report.observation_line[i], landmark_of_feature, ends);
      addEndpoints(filter, id, ends);
    }
  }
}

// The scan's point landmarks by feature index, following the scan's
// merges, for the segments' ends.
std::unordered_map<int, int> LineLandmarks::pointLandmarksByFeature(
    const IterationReport& points, const std::vector<int>& observation_feature) {
  std::unordered_map<int, int> landmark_of_feature;
  auto survivor = [&](int id) {
    for (const auto& [kept, dropped] : points.merged) {
      if (dropped == id) id = kept;
    }
    return id;
  };
  for (const PointMatch& m : points.matches) {
    landmark_of_feature[observation_feature[m.observation]] = survivor(m.landmark_id);
  }
  for (const PointMatch& m : points.created) {
    landmark_of_feature[observation_feature[m.observation]] = survivor(m.landmark_id);
  }
  return landmark_of_feature;
}

// The segments long and near enough to be used, as observations (into
// `report`) and in the map frame (returned, same order).
std::vector<LineLandmarks::Segment> LineLandmarks::gateSegments(const EkfSlam& filter,
                                                                const FeatureSet& features,
                                                                LineIterationReport* report) const {
  std::vector<Segment> segments;
  for (int l = 0; l < static_cast<int>(features.lines.size()); ++l) {
    const LineFeature& line = features.lines[l];
    if (!finiteLine(line)) {
      ++report->refused;
      continue;
    }
    if (line.length() < options_.min_length ||
        (0.5 * (line.start + line.end)).norm() > options_.max_range) {
      continue;
    }
    LineObservation obs;
    obs.z = {line.p, line.theta};
    obs.covariance = line.covariance;
    report->observations.push_back(obs);
    report->observation_line.push_back(l);
    segments.push_back(toMap(filter, line));
  }
  return segments;
}

// Individual compatibility of every segment with every overlapping
// landmark of this kind; `near_new_gate` marks the segments within some
// landmark's new-landmark gate.
std::vector<LineLandmarks::Candidate> LineLandmarks::candidatesOf(
    const EkfSlam& filter, const std::vector<Segment>& segments, const LineIterationReport& report,
    std::vector<char>* near_new_gate) const {
  Gates gates;
  gates.two = chiSquareQuantile(association_.gate_probability, 2.0);
  gates.one = chiSquareQuantile(association_.gate_probability, 1.0);
  gates.new_two = chiSquareQuantile(association_.new_landmark_probability, 2.0);
  gates.new_one = chiSquareQuantile(association_.new_landmark_probability, 1.0);
  std::vector<Candidate> candidates;
  for (int i = 0; i < static_cast<int>(segments.size()); ++i) {
    for (int slot = 0; slot < filter.landmarkCount(); ++slot) {
      if (filter.landmarkKind(slot) != kind_) continue;
      const auto track = tracks_.find(filter.landmarks()[slot].id);
      if (track == tracks_.end() || !overlaps(filter, slot, track->second, segments[i])) continue;
      Candidate c;
      bool near_new = false;
      const bool inside =
          candidate(filter, i, slot, track->second, report.observations[i], gates, &c, &near_new);
      if (near_new) (*near_new_gate)[i] = 1;
      if (inside) candidates.push_back(c);
    }
  }
  return candidates;
}

// Segment `observation` against the landmark in `slot`: true when inside
// the gate (`c` then the candidate); `near_new` when inside the
// new-landmark gate.
bool LineLandmarks::candidate(const EkfSlam& filter, int observation, int slot, const Track& track,
                              const LineObservation& obs, const Gates& gates, Candidate* out,
                              bool* near_new) const {
  Candidate& c = *out;
  const int id = filter.landmarks()[slot].id;
  c.observation = observation;
  c.landmark_id = id;
  c.match.landmark_id = id;
  if (kind_ == LandmarkKind::kLineAngle) {
    std::copy(track.endpoint_ids, track.endpoint_ids + 2, c.match.endpoint_ids);
  }
  Eigen::VectorXd innovation;
  Eigen::MatrixXd S;
  FilterStatus status = filter.predictLineMatch(obs, c.match, &innovation, &S);
  if (status != FilterStatus::kOk && kind_ == LandmarkKind::kLineAngle) {
    // Endpoints that no longer agree with the direction (θ_f beyond
    // kMaxEndpointDisagreement from their line): the direction alone.
    c.match.endpoint_ids[0] = c.match.endpoint_ids[1] = -1;
    status = filter.predictLineMatch(obs, c.match, &innovation, &S);
  }
  if (status != FilterStatus::kOk) return false;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return false;
  c.mahalanobis2 = innovation.dot(ldlt.solve(innovation));
  double log_det = std::log(ldlt.vectorD().prod());
  bool inside = c.mahalanobis2 <= (innovation.size() == 1 ? gates.one : gates.two);
  bool inside_new = c.mahalanobis2 <= (innovation.size() == 1 ? gates.new_one : gates.new_two);
  if (innovation.size() == 1) {
    // θ alone: the offset from the latest sighting as a second row.
    double offset_d2 = 0.0;
    if (!offsetCompatible(filter, slot, track, obs, &offset_d2)) return false;
    c.mahalanobis2 += offset_d2;
    log_det += std::log(offsetVariance(filter, obs) + track.latest_offset_variance);
    inside = c.mahalanobis2 <= gates.two;
    inside_new = c.mahalanobis2 <= gates.new_two;
  }
  *near_new = inside_new;
  if (!inside) return false;
  c.match.observation = observation;
  c.score = c.mahalanobis2 + log_det;
  return true;
}

// The point landmarks at the two ends of segment `line` (θ-only landmarks).
void LineLandmarks::segmentEnds(const FeatureSet& features, int l,
                                const std::unordered_map<int, int>& landmark_of_feature,
                                int ends[2]) const {
  ends[0] = ends[1] = -1;
  const LineFeature& line = features.lines[l];
  for (const auto& [feature, id] : landmark_of_feature) {
    const PointFeature& point = features.points_of_interest[feature];
    if (point.line != l && point.other_line != l) continue;
    const bool at_start =
        (point.position - line.start).norm() <= (point.position - line.end).norm();
    ends[at_start ? 0 : 1] = id;
  }
}

void LineLandmarks::addEndpoints(const EkfSlam& filter, int id, const int ends[2]) {
  Track& track = tracks_[id];
  for (int k = 0; k < 2; ++k) {
    const int e = ends[k];
    if (e < 0 || filter.slotOf(e) < 0 || e == track.endpoint_ids[0] || e == track.endpoint_ids[1]) {
      continue;
    }
    // Endpoints close together fix neither the offset nor the direction.
    const int other = track.endpoint_ids[0] >= 0 ? track.endpoint_ids[0] : track.endpoint_ids[1];
    if (other >= 0 &&
        (filter.landmarkPosition(filter.slotOf(other)) - filter.landmarkPosition(filter.slotOf(e)))
                .norm() < options_.min_length) {
      continue;
    }
    for (int& slot : track.endpoint_ids) {
      if (slot < 0) {
        slot = e;
        break;
      }
    }
  }
}

void LineLandmarks::followEndpoints(const EkfSlam& filter,
                                    const std::vector<std::pair<int, int>>& merged) {
  for (auto& entry : tracks_) {
    for (int& e : entry.second.endpoint_ids) {
      for (const auto& [kept, dropped] : merged) {
        if (e == dropped) e = kept;
      }
      if (e >= 0 && filter.slotOf(e) < 0) e = -1;
    }
  }
}

void LineLandmarks::synchronise(const EkfSlam& filter) {
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    if (filter.slotOf(it->first) < 0) {
      it = tracks_.erase(it);
    } else {
      ++it;
    }
  }
  followEndpoints(filter, {});
  refreshSupport(filter);
}

void LineLandmarks::reanchor(const std::vector<std::pair<int, Pose2>>& corrections) {
  for (const auto& [id, correction] : corrections) {
    const auto it = tracks_.find(id);
    if (it == tracks_.end()) continue;
    Track& track = it->second;
    track.first = transformFrom(correction, track.first);
    track.last = transformFrom(correction, track.last);
    track.latest_mid = transformFrom(correction, track.latest_mid);
  }
}

void LineLandmarks::seed(const EkfSlam& filter,
                         const std::unordered_map<int, LineSupport>& support) {
  for (const auto& [id, given] : support) {
    const int slot = filter.slotOf(id);
    if (slot < 0 || filter.landmarkKind(slot) != kind_) continue;
    Track track;
    track.endpoint_ids[0] = given.endpoint_ids[0];
    track.endpoint_ids[1] = given.endpoint_ids[1];
    if (kind_ == LandmarkKind::kLine) {
      const PolarLine line = filter.lineLandmark(slot);
      const Vector2 foot = line.p * Vector2(std::cos(line.theta), std::sin(line.theta));
      const Vector2 d = direction(line.theta);
      track.first = foot + given.s_min * d;
      track.last = foot + given.s_max * d;
      track.latest_offset_variance = filter.landmarkCovariance(slot)(0, 0);
    } else {
      std::vector<int> ends;  // slots of the endpoint points
      for (int e : given.endpoint_ids) {
        const int end_slot = e >= 0 ? filter.slotOf(e) : -1;
        if (end_slot >= 0 && filter.landmarkKind(end_slot) == LandmarkKind::kPoint) {
          ends.push_back(end_slot);
        }
      }
      if (ends.empty()) continue;
      track.first = filter.landmarkPosition(ends.front());
      track.last = filter.landmarkPosition(ends.back());
      // The offset across the line is known as well as its first end.
      const double theta = filter.lineAngle(slot);
      const Vector2 normal(std::cos(theta), std::sin(theta));
      track.latest_offset_variance = normal.dot(filter.landmarkCovariance(ends.front()) * normal);
    }
    track.latest_mid = 0.5 * (track.first + track.last);
    tracks_[id] = track;
  }
  refreshSupport(filter);
}

void LineLandmarks::refreshSupport(const EkfSlam& filter) {
  support_.clear();
  for (const auto& [id, track] : tracks_) {
    const int slot = filter.slotOf(id);
    if (slot < 0) continue;
    const Vector2 d = direction(landmarkTheta(filter, slot));
    LineSupport& s = support_[id];
    s.s_min = std::min(d.dot(track.first), d.dot(track.last));
    s.s_max = std::max(d.dot(track.first), d.dot(track.last));
    s.endpoint_ids[0] = track.endpoint_ids[0];
    s.endpoint_ids[1] = track.endpoint_ids[1];
  }
}

std::vector<Segment2> LineLandmarks::walls(const EkfSlam& filter) const {
  std::vector<int> ids;
  for (const auto& entry : tracks_) {
    if (filter.slotOf(entry.first) >= 0) ids.push_back(entry.first);
  }
  std::sort(ids.begin(), ids.end());
  std::vector<Segment2> out;
  out.reserve(ids.size());
  for (int id : ids) {
    const Track& track = tracks_.at(id);
    out.push_back({track.first, track.last});
  }
  return out;
}

}  // namespace ekf_slam
