// The full smoother's problem over a pipeline's kept history, as a value.
// SlamPipeline::smoothingProblem() copies it out (after waiting for the
// back end); solve() runs the batch optimisation on whatever thread holds
// it, while the pipeline goes on with new scans. A live node smooths this
// way so that scans and tf keep flowing during a long solve.
#pragma once

#include <vector>

#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/pipeline/scan_history.h"
#include "ekf_slam_core/smoother/full_smoother.h"

namespace ekf_slam {

struct SmoothingProblem {
  ScanHistory history;  // the scans and iterations to smooth (and their readings, if kept)
  EkfSlam filter;       // the landmarks the sightings start from
  std::vector<IterationConstraint> loops;  // the back end's loop edges between iterations
  std::vector<Pose2> initial;              // loop-closed starting poses; empty: the filter's
  FullSmootherOptions options;

  // Poses for every kept scan from the full smoother's iteration poses;
  // with a bounded history the smoother is anchored at the oldest kept
  // iteration, where the loop-closed graph has it. `details` and
  // `last_problem` as in smoothFull.
  std::vector<StampedPose> solve(FullSmootherResult* details = nullptr,
                                 LandmarkGraph* last_problem = nullptr) const;
};

// SmoothingProblem::solve on the parts where they lie (no copy: a
// pipeline solved on its own thread, as the offline runner does).
std::vector<StampedPose> solveSmoothing(const ScanHistory& history, const EkfSlam& filter,
                                        const std::vector<IterationConstraint>& loops,
                                        const std::vector<Pose2>& initial,
                                        const FullSmootherOptions& options,
                                        FullSmootherResult* details, LandmarkGraph* last_problem);

}  // namespace ekf_slam
