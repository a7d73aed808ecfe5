#include "ekf_slam_ros/slam_node/slam_messages.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "ekf_slam_core/filter/chi_square.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace {

const char* kindName(PointKind kind) {
  return kind == PointKind::kCorner ? "corner" : "segment_end";
}

const char* contextName(EndpointContext context) {
  switch (context) {
    case EndpointContext::kCorner:
      return "corner";
    case EndpointContext::kFrontEdge:
      return "front_edge";
    case EndpointContext::kOccluded:
      return "occluded";
    case EndpointContext::kNoReturn:
      return "no_return";
    case EndpointContext::kScanBoundary:
      return "scan_boundary";
    case EndpointContext::kUnresolved:
      return "unresolved";
  }
  return "unknown";
}

Matrix2 matrixOf(const boost::array<double, 4>& values) {
  Matrix2 m;
  m << values[0], values[1], values[2], values[3];
  return m;
}

void copy(const Matrix2& m, boost::array<double, 4>* out) {
  (*out)[0] = m(0, 0);
  (*out)[1] = m(0, 1);
  (*out)[2] = m(1, 0);
  (*out)[3] = m(1, 1);
}

geometry_msgs::Point point(double x, double y, double z = 0.0) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

std_msgs::ColorRGBA colour(float r, float g, float b, float a = 1.0f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

visualization_msgs::Marker marker(const std_msgs::Header& header, const std::string& ns, int id,
                                  int type) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = m.scale.z = 1.0;
  return m;
}

// A flat cylinder whose footprint is the ellipse (rviz scales a unit-diameter
// cylinder: scale.x/y are the full axes, i.e. twice the semi-axes).
visualization_msgs::Marker ellipseMarker(const std_msgs::Header& header, const std::string& ns,
                                         int id, const Vector2& centre, const Matrix2& covariance,
                                         double probability, const std_msgs::ColorRGBA& c) {
  const CovarianceEllipse e = covarianceEllipse(covariance, probability);
  visualization_msgs::Marker m = marker(header, ns, id, visualization_msgs::Marker::CYLINDER);
  m.pose.position = point(centre.x(), centre.y());
  m.pose.orientation = ros_conversions::quaternionOfYaw(e.angle);
  // rviz refuses zero scales; a perfectly known point is drawn 1 mm wide.
  m.scale.x = std::max(2.0 * e.semi_major, 1e-3);
  m.scale.y = std::max(2.0 * e.semi_minor, 1e-3);
  m.scale.z = 0.01;
  m.color = c;
  return m;
}

const std_msgs::ColorRGBA kTentative = colour(0.6f, 0.6f, 0.6f, 0.6f);

visualization_msgs::Marker lineList(const std_msgs::Header& header, const std::string& ns, int id,
                                    double width, const std_msgs::ColorRGBA& c) {
  visualization_msgs::Marker m = marker(header, ns, id, visualization_msgs::Marker::LINE_LIST);
  m.scale.x = width;
  m.color = c;
  return m;
}

void addSegment(const Vector2& a, const Vector2& b, visualization_msgs::Marker* m) {
  m->points.push_back(point(a.x(), a.y()));
  m->points.push_back(point(b.x(), b.y()));
}

// The direction along a line whose normal points at `normal_angle`.
Vector2 lineDirection(double normal_angle) {
  return Vector2(-std::sin(normal_angle), std::cos(normal_angle));
}

// The (p, θ) line in `slot`: its segment and its band (landmarkMarkers'
// contract); returns where its label goes.
Vector2 addLineMarkers(const EkfSlam& filter, int slot, const LineSupport* support, double k,
                       const std_msgs::Header& header, visualization_msgs::MarkerArray* out) {
  const LandmarkInfo& info = filter.landmarks()[slot];
  const bool tentative = info.observations <= 1;
  const PolarLine line = filter.lineLandmark(slot);
  const Vector2 normal(std::cos(line.theta), std::sin(line.theta));
  const Vector2 along = lineDirection(line.theta);
  const Vector2 foot = line.p * normal;
  const double s_min = support ? support->s_min : -0.5 * kUnknownExtentLength;
  const double s_max = support ? support->s_max : 0.5 * kUnknownExtentLength;
  visualization_msgs::Marker segment =
      lineList(header, "line_landmarks", info.id, 0.05,
               tentative ? kTentative : colour(0.2f, 0.4f, 1.0f, 0.9f));
  addSegment(foot + s_min * along, foot + s_max * along, &segment);
  out->markers.push_back(segment);
  // A point at s along the line moves across it by dp − s dθ, so its
  // variance there is σ_p² − 2s σ_pθ + s² σ_θ²: a hyperbola in s, drawn as
  // a polyline of kPieces pieces per side (smooth enough at rviz's scale).
  constexpr int kPieces = 8;
  const Matrix2 c = filter.landmarkCovariance(slot);
  visualization_msgs::Marker band =
      lineList(header, "line_landmark_bands", info.id, 0.01,
               tentative ? kTentative : colour(0.5f, 0.7f, 1.0f, 0.7f));
  for (double side : {-1.0, 1.0}) {
    auto edge = [&](int i) {
      const double s = s_min + (s_max - s_min) * i / kPieces;
      const double variance = c(0, 0) - 2.0 * s * c(0, 1) + s * s * c(1, 1);
      return Vector2(foot + s * along + side * k * std::sqrt(std::max(variance, 0.0)) * normal);
    };
    for (int i = 0; i < kPieces; ++i) addSegment(edge(i), edge(i + 1), &band);
  }
  out->markers.push_back(band);
  return foot + 0.5 * (s_min + s_max) * along;
}

// The θ-only line in `slot`: its segment and its fan (landmarkMarkers'
// contract); returns where its label goes, or nothing when no endpoint
// point gives it a place.
std::optional<Vector2> addLineAngleMarkers(const EkfSlam& filter, int slot,
                                           const LineSupport* support, double k,
                                           const std_msgs::Header& header,
                                           visualization_msgs::MarkerArray* out) {
  const LineSupport none;  // no endpoints
  std::vector<Vector2> ends;
  for (int id : (support ? *support : none).endpoint_ids) {
    const int endpoint = filter.slotOf(id);
    if (endpoint >= 0 && filter.landmarkKind(endpoint) == LandmarkKind::kPoint) {
      ends.push_back(filter.landmarkPosition(endpoint));
    }
  }
  if (ends.empty()) return std::nullopt;
  const LandmarkInfo& info = filter.landmarks()[slot];
  const bool tentative = info.observations <= 1;
  const double theta = filter.lineAngle(slot);
  if (ends.size() == 1) {
    const Vector2 half = 0.5 * kUnknownExtentLength * lineDirection(theta);
    ends = {ends[0] - half, ends[0] + half};
  }
  const Vector2 middle = 0.5 * (ends[0] + ends[1]);
  const double half_length = 0.5 * (ends[1] - ends[0]).norm();
  visualization_msgs::Marker segment =
      lineList(header, "line_angle_landmarks", info.id, 0.05,
               tentative ? kTentative : colour(0.7f, 0.3f, 0.9f, 0.9f));
  addSegment(ends[0], ends[1], &segment);
  out->markers.push_back(segment);
  visualization_msgs::Marker fan =
      lineList(header, "line_angle_fans", info.id, 0.01,
               tentative ? kTentative : colour(0.85f, 0.6f, 1.0f, 0.7f));
  const double spread = k * std::sqrt(std::max(filter.lineAngleVariance(slot), 0.0));
  for (double side : {-1.0, 1.0}) {
    const Vector2 half = half_length * lineDirection(theta + side * spread);
    addSegment(middle - half, middle + half, &fan);
  }
  out->markers.push_back(fan);
  return middle;
}

}  // namespace

CovarianceEllipse covarianceEllipse(const Matrix2& covariance, double probability) {
  const Matrix2 c = 0.5 * (covariance + covariance.transpose());
  CovarianceEllipse e;
  if (!c.allFinite()) return e;
  Eigen::SelfAdjointEigenSolver<Matrix2> solver(c);
  const Vector2 lambda = solver.eigenvalues().cwiseMax(0.0);  // ascending
  const double k = chiSquareQuantile(probability, 2.0);
  e.semi_major = std::sqrt(k * lambda(1));
  e.semi_minor = std::sqrt(k * lambda(0));
  const Vector2 major = solver.eigenvectors().col(1);
  e.angle = std::atan2(major.y(), major.x());
  return e;
}

Features toFeaturesMessage(const FeatureSet& features, const std_msgs::Header& header) {
  Features out;
  out.header = header;
  for (const PointFeature& p : features.points_of_interest) {
    FeaturePoint m;
    m.x = p.position.x();
    m.y = p.position.y();
    copy(p.covariance, &m.covariance);
    m.range = p.range;
    m.bearing = p.bearing;
    copy(p.range_bearing_covariance, &m.range_bearing_covariance);
    m.kind = kindName(p.kind);
    m.context = contextName(p.context);
    m.landmark_candidate = p.landmark_candidate;
    out.points.push_back(m);
  }
  for (const LineFeature& l : features.lines) {
    FeatureLine m;
    m.p = l.p;
    m.theta = l.theta;
    copy(l.covariance, &m.covariance);
    m.start = point(l.start.x(), l.start.y());
    m.end = point(l.end.x(), l.end.y());
    m.num_points = l.num_points;
    m.rms_residual = l.rms_residual;
    out.lines.push_back(m);
  }
  return out;
}

bool fromFeaturesMessage(const Features& message, FeatureSet* features, std::string* error) {
  *features = FeatureSet{};
  constexpr EndpointContext kContexts[] = {
      EndpointContext::kCorner,   EndpointContext::kFrontEdge,    EndpointContext::kOccluded,
      EndpointContext::kNoReturn, EndpointContext::kScanBoundary, EndpointContext::kUnresolved,
  };
  for (size_t i = 0; i < message.points.size(); ++i) {
    const FeaturePoint& m = message.points[i];
    PointFeature p;
    if (m.kind == kindName(PointKind::kCorner)) {
      p.kind = PointKind::kCorner;
    } else if (m.kind == kindName(PointKind::kSegmentEnd)) {
      p.kind = PointKind::kSegmentEnd;
    } else {
      *error =
          "point " + std::to_string(i) + ": unknown kind '" + m.kind + "' (corner or segment_end)";
      return false;
    }
    bool known_context = false;
    for (EndpointContext context : kContexts) {
      if (m.context == contextName(context)) {
        p.context = context;
        known_context = true;
      }
    }
    if (!known_context) {
      *error = "point " + std::to_string(i) + ": unknown context '" + m.context + "'";
      return false;
    }
    p.landmark_candidate = m.landmark_candidate;
    p.position = Vector2(m.x, m.y);
    p.covariance = matrixOf(m.covariance);
    p.range = m.range;
    p.bearing = m.bearing;
    p.range_bearing_covariance = matrixOf(m.range_bearing_covariance);
    features->points_of_interest.push_back(p);
  }
  for (const FeatureLine& m : message.lines) {
    LineFeature l;
    l.p = m.p;
    l.theta = m.theta;
    l.covariance = matrixOf(m.covariance);
    l.start = Vector2(m.start.x, m.start.y);
    l.end = Vector2(m.end.x, m.end.y);
    l.num_points = m.num_points;
    l.rms_residual = m.rms_residual;
    features->lines.push_back(l);
  }
  return true;
}

LandmarkMap toLandmarkMapMessage(const LandmarkMapFile& map, const std_msgs::Header& header) {
  LandmarkMap out;
  out.header = header;
  out.landmarks.reserve(map.landmarks.size());
  for (const LandmarkRecord& r : map.landmarks) {
    Landmark m;
    m.id = r.id;
    m.x = r.position.x();
    m.y = r.position.y();
    copy(r.covariance, &m.covariance);
    m.observations = r.observations;
    m.tentative = r.observations <= 1;
    out.landmarks.push_back(m);
  }
  for (const LineLandmarkRecord& r : map.lines) {
    LineLandmark m;
    m.id = r.id;
    m.p = r.p;
    m.theta = r.theta;
    copy(r.covariance, &m.covariance);
    m.observations = r.observations;
    m.tentative = r.observations <= 1;
    m.extent_known = r.has_extent;
    m.s_min = r.s_min;
    m.s_max = r.s_max;
    out.lines.push_back(m);
  }
  for (const LineAngleRecord& r : map.line_angles) {
    LineAngleLandmark m;
    m.id = r.id;
    m.theta = r.theta;
    m.variance = r.variance;
    m.observations = r.observations;
    m.tentative = r.observations <= 1;
    m.endpoint_ids = {r.endpoint_ids[0], r.endpoint_ids[1]};
    out.line_angles.push_back(m);
  }
  return out;
}

AssociationReport toAssociationReport(const std::vector<PointObservation>& observations,
                                      const IterationReport& iteration,
                                      const std_msgs::Header& header) {
  AssociationReport out;
  out.header = header;
  const AssociationResult& association = iteration.association;
  // New landmarks got their ids in the order of newLandmarks(); when some
  // augmentations were refused (localisation only) the pairing is unknown.
  const std::vector<int> new_observations = association.newLandmarks();
  const bool new_ids_known = iteration.augment_failures == 0 &&
                             new_observations.size() == iteration.new_landmark_ids.size();
  for (size_t i = 0; i < association.observations.size() && i < observations.size(); ++i) {
    const ObservationAssociation& a = association.observations[i];
    ObservationReport m;
    m.range = observations[i].z.range;
    m.bearing = observations[i].z.bearing;
    m.gate = association.gate;
    m.new_landmark_gate = association.new_landmark_gate;
    m.decision = toString(a.decision);
    m.landmark_id = -1;
    if (a.decision == AssociationDecision::kMatched &&
        iteration.update_status == FilterStatus::kOk) {
      m.landmark_id = a.landmark_id;
    } else if (a.decision == AssociationDecision::kMatched) {
      m.decision = "update_refused";
    }
    if (a.decision == AssociationDecision::kNewLandmark && new_ids_known) {
      const auto it =
          std::find(new_observations.begin(), new_observations.end(), static_cast<int>(i));
      m.landmark_id = iteration.new_landmark_ids[it - new_observations.begin()];
    }
    for (const AssociationCandidate& c : a.candidates) {
      LandmarkCandidate candidate;
      candidate.landmark_id = c.landmark_id;
      candidate.mahalanobis_sq = c.mahalanobis2;
      m.candidates.push_back(candidate);
    }
    out.observations.push_back(m);
  }
  return out;
}

visualization_msgs::MarkerArray featureMarkers(const FeatureSet& features,
                                               const std_msgs::Header& header) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker lines =
      marker(header, "feature_lines", 0, visualization_msgs::Marker::LINE_LIST);
  lines.scale.x = 0.03;
  lines.color = colour(0.1f, 0.6f, 1.0f);
  for (const LineFeature& l : features.lines) {
    lines.points.push_back(point(l.start.x(), l.start.y()));
    lines.points.push_back(point(l.end.x(), l.end.y()));
  }
  visualization_msgs::Marker candidates =
      marker(header, "feature_landmark_candidates", 0, visualization_msgs::Marker::SPHERE_LIST);
  candidates.scale.x = candidates.scale.y = candidates.scale.z = 0.12;
  candidates.color = colour(1.0f, 0.5f, 0.0f);
  visualization_msgs::Marker others =
      marker(header, "feature_other_points", 0, visualization_msgs::Marker::SPHERE_LIST);
  others.scale.x = others.scale.y = others.scale.z = 0.08;
  others.color = colour(0.6f, 0.6f, 0.6f, 0.8f);
  for (const PointFeature& p : features.points_of_interest) {
    (p.landmark_candidate ? candidates : others)
        .points.push_back(point(p.position.x(), p.position.y()));
  }
  // An empty list would be rejected by rviz; DELETE clears the last one instead.
  for (visualization_msgs::Marker* m : {&lines, &candidates, &others}) {
    if (m->points.empty()) m->action = visualization_msgs::Marker::DELETE;
    out.markers.push_back(*m);
  }
  return out;
}

visualization_msgs::MarkerArray landmarkMarkers(const EkfSlam& filter,
                                                const std::unordered_map<int, LineSupport>& support,
                                                const IterationReport* iteration,
                                                const std_msgs::Header& header,
                                                double probability) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker clear = marker(header, "", 0, visualization_msgs::Marker::CUBE);
  clear.action = visualization_msgs::Marker::DELETEALL;
  out.markers.push_back(clear);
  // Per parameter, two-sided: the same probability as the ellipses' region.
  const double k = std::sqrt(chiSquareQuantile(probability, 1.0));
  for (int s = 0; s < filter.landmarkCount(); ++s) {
    const LandmarkInfo& info = filter.landmarks()[s];
    const bool tentative = info.observations <= 1;
    const auto seen = support.find(info.id);
    const LineSupport* line_support = seen == support.end() ? nullptr : &seen->second;
    std::optional<Vector2> label_at;
    switch (info.kind) {
      case LandmarkKind::kPoint:
        label_at = filter.landmarkPosition(s);
        out.markers.push_back(ellipseMarker(
            header, "landmark_ellipses", info.id, *label_at, filter.landmarkCovariance(s),
            probability, tentative ? kTentative : colour(0.1f, 0.8f, 0.2f, 0.7f)));
        break;
      case LandmarkKind::kLine:
        label_at = addLineMarkers(filter, s, line_support, k, header, &out);
        break;
      case LandmarkKind::kLineAngle:
        label_at = addLineAngleMarkers(filter, s, line_support, k, header, &out);
        break;
    }
    if (!label_at) continue;
    visualization_msgs::Marker label =
        marker(header, "landmark_ids", info.id, visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.pose.position = point(label_at->x(), label_at->y(), 0.25);
    label.scale.z = 0.2;
    label.color = colour(1.0f, 1.0f, 1.0f);
    label.text = std::to_string(info.id);
    out.markers.push_back(label);
  }
  const Pose2 robot = filter.pose();
  out.markers.push_back(ellipseMarker(header, "robot_ellipse", 0, Vector2(robot.x, robot.y),
                                      filter.poseCovariance().topLeftCorner<2, 2>(), probability,
                                      colour(1.0f, 0.2f, 0.2f, 0.6f)));
  if (iteration != nullptr) {
    visualization_msgs::Marker lines =
        marker(header, "associations", 0, visualization_msgs::Marker::LINE_LIST);
    lines.scale.x = 0.02;
    lines.color = colour(1.0f, 1.0f, 0.0f);
    const Vector2 laser = transformFrom(robot, filter.options().laser_pose.translation());
    for (const PointMatch& match : iteration->matches) {
      const int slot = filter.slotOf(match.landmark_id);
      if (slot < 0) continue;  // pruned since
      lines.points.push_back(point(laser.x(), laser.y()));
      const Vector2 p = filter.landmarkPosition(slot);
      lines.points.push_back(point(p.x(), p.y()));
    }
    if (!lines.points.empty()) out.markers.push_back(lines);
  }
  return out;
}

visualization_msgs::MarkerArray poseGraphMarkers(const std::vector<Pose2>& key_poses,
                                                 const std::vector<LoopLink>& loops,
                                                 const std_msgs::Header& header) {
  visualization_msgs::Marker nodes =
      marker(header, "pose_graph_nodes", 0, visualization_msgs::Marker::SPHERE_LIST);
  nodes.scale.x = nodes.scale.y = nodes.scale.z = 0.08;
  nodes.color = colour(0.3f, 0.5f, 1.0f);
  visualization_msgs::Marker edges =
      lineList(header, "pose_graph_edges", 0, 0.015, colour(0.5f, 0.6f, 0.9f, 0.8f));
  visualization_msgs::Marker closed =
      lineList(header, "pose_graph_loops", 0, 0.03, colour(1.0f, 0.3f, 0.1f));
  visualization_msgs::Marker heading =
      lineList(header, "pose_graph_heading_loops", 0, 0.015, colour(1.0f, 0.8f, 0.1f, 0.8f));
  const int count = static_cast<int>(key_poses.size());
  for (int k = 0; k < count; ++k) {
    const Vector2 at = key_poses[k].translation();
    nodes.points.push_back(point(at.x(), at.y()));
    if (k > 0) addSegment(key_poses[k - 1].translation(), at, &edges);
  }
  for (const LoopLink& link : loops) {
    if (link.from < 0 || link.to < 0 || link.from >= count || link.to >= count) continue;
    addSegment(key_poses[link.from].translation(), key_poses[link.to].translation(),
               link.heading_only ? &heading : &closed);
  }
  visualization_msgs::MarkerArray out;
  for (visualization_msgs::Marker* m : {&nodes, &edges, &closed, &heading}) {
    if (m->points.empty()) m->action = visualization_msgs::Marker::DELETE;
    out.markers.push_back(*m);
  }
  return out;
}

}  // namespace ekf_slam
