// Ceres as the reference solver of the hand-written Levenberg–Marquardt
// (pose_graph.h, landmark_graph.h): the tests solve the same problems both
// ways and compare the optima, and solver_comparison does so on the real
// logs' exported problems (docs/solvers.md). Nothing in the pipeline links
// this library.
#pragma once

#include "ekf_slam_core/pose_graph/landmark_graph.h"
#include "ekf_slam_core/pose_graph/pose_graph.h"

namespace ekf_slam {

// Ceres's Levenberg–Marquardt on `graph` from its current poses, node 0
// fixed: at most options.max_iterations steps, stopping once a step lowers
// the cost by less than 1e-6 of it (convergence_step unused); the same first
// damping (1 / initial_lambda as the trust region).
PoseGraphSummary solveWithCeres(const PoseGraphOptions& options, PoseGraph* graph);
// The same for a landmark graph; min_relative_decrease is Ceres's function
// tolerance.
LandmarkGraphSummary solveWithCeres(const LandmarkGraphOptions& options, LandmarkGraph* graph);

}  // namespace ekf_slam
