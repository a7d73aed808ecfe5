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
#include <vector>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/io/landmark_map.h"

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

// The filter's map in the map frame (`header`), marginal covariances.
LandmarkMap toLandmarkMapMessage(const EkfSlam& filter, const std_msgs::Header& header);
LandmarkMapFile toLandmarkMapFile(const EkfSlam& filter, const std::string& frame);

// One entry per observation of the iteration; `header` = scan stamp + laser frame.
AssociationReport toAssociationReport(const std::vector<PointObservation>& observations,
                                      const IterationReport& iteration,
                                      const std_msgs::Header& header);

// rviz view of the features (frame of `header`): lines as a LINE_LIST,
// landmark candidates as orange spheres, other points grey.
visualization_msgs::MarkerArray featureMarkers(const FeatureSet& features,
                                               const std_msgs::Header& header);

// rviz view of the filter (map frame in `header`): each landmark as a flat
// cylinder at its covariance ellipse (namespace "landmark_ellipses", marker
// id = landmark id; tentative ones grey), a text label with its id
// ("landmark_ids"), the robot's position ellipse ("robot_ellipse") and, when
// `iteration` is given, lines from the laser to every matched landmark
// ("associations"). Starts with a DELETEALL so removed landmarks vanish.
visualization_msgs::MarkerArray landmarkMarkers(const EkfSlam& filter,
                                                const IterationReport* iteration,
                                                const std_msgs::Header& header, double probability);

}  // namespace ekf_slam
