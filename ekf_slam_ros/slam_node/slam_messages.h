// Core results → this package's messages and rviz markers, for feature_node
// and ekf_slam_node (one file per message family, as in the conversions
// folder). Pure functions: no node handle, no clock; every message gets the
// header it is given (the scan's stamp = data time).
#pragma once

#include <ekf_slam/AssociationReport.h>
#include <ekf_slam/Features.h>
#include <ekf_slam/LandmarkMap.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/filter/line_support.h"
#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/loop_closure/back_end.h"

namespace ekf_slam {

// The ellipse {p : (p − μ)ᵀ C⁻¹ (p − μ) ≤ k} with k = χ²₂ quantile of
// `probability` (95 %: k = 5.991): semi-axes sqrt(k·λᵢ) along C's
// eigenvectors. `angle` (rad) is the direction of the major axis.
struct CovarianceEllipse {
  double semi_major = 0.0;  // m
  double semi_minor = 0.0;  // m
  double angle = 0.0;       // rad, in the covariance's frame
};
CovarianceEllipse covarianceEllipse(const Matrix2& covariance, double probability);

// Features of one scan, in the scan's frame (`header`).
Features toFeaturesMessage(const FeatureSet& features, const std_msgs::Header& header);

// Back from the message, for ekf_slam_node's `input: features` mode: the
// points (with kind, context and candidate flag) and lines. The links between
// points and lines (PointFeature::line) and the raw readings are not in the
// message and stay empty. False with `error` naming the point and field when
// a kind or context string is unknown; values are checked later by
// validateFeatureSet.
bool fromFeaturesMessage(const Features& message, FeatureSet* features, std::string* error);

// A landmark map (the filter's through toLandmarkMapFile, or a loaded one)
// as the message, in the map frame (`header`): each kind in its own list,
// marginal covariances, tentative = seen once.
LandmarkMap toLandmarkMapMessage(const LandmarkMapFile& map, const std_msgs::Header& header);

// One entry per observation of the iteration; `header` = scan stamp + laser frame.
AssociationReport toAssociationReport(const std::vector<PointObservation>& observations,
                                      const IterationReport& iteration,
                                      const std_msgs::Header& header);

// rviz view of the features (frame of `header`): lines as a LINE_LIST,
// landmark candidates as orange spheres, other points grey.
visualization_msgs::MarkerArray featureMarkers(const FeatureSet& features,
                                               const std_msgs::Header& header);

// rviz view of the filter (map frame in `header`), marker id = landmark id,
// tentative landmarks grey:
//   - each point as a flat cylinder at its covariance ellipse
//     ("landmark_ellipses");
//   - each (p, θ) line as a segment over its seen extent ("line_landmarks";
//     from `support`, else a kUnknownExtentLength stub centred on the foot
//     point), with its uncertainty ("line_landmark_bands"): two thin
//     polylines at ±k σ(s) either side, where σ(s)² = σ_p² − 2s σ_pθ +
//     s² σ_θ² is the variance of the wall's position across it at s along
//     it, and k the two-sided quantile of `probability` (1.96 for 95 %).
//     The band is narrowest where the wall is best known and widens with
//     the θ uncertainty away from there: one shape for both parameters;
//   - each θ-only line between its endpoint points ("line_angle_landmarks";
//     a kUnknownExtentLength stub through the one endpoint when it has one,
//     nothing without), with a fan of two thin segments through the
//     midpoint at θ ± k σ_θ ("line_angle_fans"), as long as the segment: how
//     far the direction's own estimate lets the wall's ends swing;
//   - a text label with each drawn landmark's id ("landmark_ids"), the
//     robot's position ellipse ("robot_ellipse") and, when `iteration` is
//     given, lines from the laser to every matched point ("associations").
// Starts with a DELETEALL so removed landmarks vanish.
constexpr double kUnknownExtentLength = 2.0;  // m
visualization_msgs::MarkerArray landmarkMarkers(const EkfSlam& filter,
                                                const std::unordered_map<int, LineSupport>& support,
                                                const IterationReport* iteration,
                                                const std_msgs::Header& header, double probability);

// rviz view of the loop-closing pose graph (map frame in `header`): the key
// scans' positions ("pose_graph_nodes"), the sequential edges joining
// consecutive key scans ("pose_graph_edges"), the loops
// ("pose_graph_loops") and the heading-only edges between the walls of one
// place ("pose_graph_heading_loops"). `loops` index `key_poses`; a link
// naming a key beyond them is left out. An empty list is sent as a DELETE
// of its marker (rviz refuses empty lists).
visualization_msgs::MarkerArray poseGraphMarkers(const std::vector<Pose2>& key_poses,
                                                 const std::vector<LoopLink>& loops,
                                                 const std_msgs::Header& header);

}  // namespace ekf_slam
