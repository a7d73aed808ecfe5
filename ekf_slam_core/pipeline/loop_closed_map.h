// The filter's map where the loop-closed estimate puts it, for drawing and
// publishing in the `map` frame. Between the back end's optimisations the
// filter keeps the geometry of its last re-anchoring, while the graph (and
// with it the published pose and grid) may have moved since, by heading
// loops and by the loops' own refinement. Drawn in the filter's frame, the
// landmarks sat metres off the grid mid-run.
//
// The view moves each piece as re-anchoring would move it now: the robot
// onto the causal estimate, each landmark with the key scan it hangs off
// (a point landmark from where the filter had it right after its latest
// sighting: BackEndLink::landmarkCorrections), a (p, θ) line's seen extent
// with its line. Landmarks hanging off no key scan (seeded from a map file) stay.
// Without loop closure the causal estimate is the filter's pose and the
// view is the filter itself.
#pragma once

#include <unordered_map>

#include "ekf_slam_core/pipeline/slam_pipeline.h"

namespace ekf_slam {

struct LoopClosedMap {
  EkfSlam filter;                                // a re-anchored copy of the pipeline's
  std::unordered_map<int, LineSupport> support;  // the lines' extents along the moved lines
};

// `causal`: the loop-closed pose of the robot at the pipeline's last
// iteration (ScanResult::causal_pose of that scan).
LoopClosedMap loopClosedMap(const SlamPipeline& pipeline, const Pose2& causal);

}  // namespace ekf_slam
