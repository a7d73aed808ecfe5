// The filter's landmarks ↔ the landmark map file (io/landmark_map.h), for
// every landmark kind: what the live node's save_map / load_map and the
// offline runner's landmarks.yaml go through, so that both write the same
// records.
//
// The filter holds each landmark's mean and covariance; what it does not
// hold about a line landmark (the stretch that was seen, a θ-only line's
// endpoint points) comes from the pipeline's LineSupport per landmark id
// and goes back into one on loading.
#pragma once

#include <string>
#include <unordered_map>

#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/filter/line_support.h"
#include "ekf_slam_core/io/landmark_map.h"

namespace ekf_slam {

// One record per landmark, in slot order within each kind: the marginal
// mean and covariance, the number of observations and, for lines, the
// extent and endpoints of `support` (a line without an entry there is
// written without an extent; an endpoint id that names no point landmark of
// the filter, one merged or pruned since, is written as -1 so that the file
// loads again).
LandmarkMapFile toLandmarkMapFile(const EkfSlam& filter,
                                  const std::unordered_map<int, LineSupport>& support,
                                  const std::string& frame);

// Seeds `filter` with every landmark of `map` as a prior (EkfSlam::
// addLandmark, addLineLandmark, addLineAngleLandmark: uncorrelated with the
// pose and each other, ids kept), points first so that θ-only lines find
// their endpoints. `support` (if given) receives each line's extent and
// endpoint ids; an endpoint whose point was refused becomes -1. Returns how
// many landmarks the filter refused (a duplicate id, a prior it cannot
// represent); the others are seeded.
int seedFilter(const LandmarkMapFile& map, EkfSlam* filter,
               std::unordered_map<int, LineSupport>* support = nullptr);

}  // namespace ekf_slam
