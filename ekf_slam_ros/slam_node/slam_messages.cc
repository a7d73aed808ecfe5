#include "ekf_slam_ros/slam_node/slam_messages.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_ros/conversions/pose_conversion.h"

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

LandmarkMap toLandmarkMapMessage(const EkfSlam& filter, const std_msgs::Header& header) {
  LandmarkMap out;
  out.header = header;
  out.landmarks.reserve(filter.landmarkCount());
  for (int s = 0; s < filter.landmarkCount(); ++s) {
    Landmark m;
    m.id = filter.landmarks()[s].id;
    m.x = filter.landmarkPosition(s).x();
    m.y = filter.landmarkPosition(s).y();
    copy(filter.landmarkCovariance(s), &m.covariance);
    m.observations = filter.landmarks()[s].observations;
    m.tentative = m.observations <= 1;
    out.landmarks.push_back(m);
  }
  return out;
}

LandmarkMapFile toLandmarkMapFile(const EkfSlam& filter, const std::string& frame) {
  LandmarkMapFile out;
  out.frame = frame;
  for (int s = 0; s < filter.landmarkCount(); ++s) {
    LandmarkRecord r;
    r.id = filter.landmarks()[s].id;
    r.position = filter.landmarkPosition(s);
    r.covariance = filter.landmarkCovariance(s);
    r.observations = filter.landmarks()[s].observations;
    out.landmarks.push_back(r);
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
                                                const IterationReport* iteration,
                                                const std_msgs::Header& header,
                                                double probability) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker clear = marker(header, "", 0, visualization_msgs::Marker::CUBE);
  clear.action = visualization_msgs::Marker::DELETEALL;
  out.markers.push_back(clear);
  for (int s = 0; s < filter.landmarkCount(); ++s) {
    const LandmarkInfo& info = filter.landmarks()[s];
    const bool tentative = info.observations <= 1;
    const Vector2 p = filter.landmarkPosition(s);
    out.markers.push_back(ellipseMarker(
        header, "landmark_ellipses", info.id, p, filter.landmarkCovariance(s), probability,
        tentative ? colour(0.6f, 0.6f, 0.6f, 0.6f) : colour(0.1f, 0.8f, 0.2f, 0.7f)));
    visualization_msgs::Marker label =
        marker(header, "landmark_ids", info.id, visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.pose.position = point(p.x(), p.y(), 0.25);
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

}  // namespace ekf_slam
