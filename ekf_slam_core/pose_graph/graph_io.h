// Text files for the two sparse least-squares problems of this folder, so
// that a problem met in a run (the loop-closure pose graph, the full
// smoother's landmark graph) can be solved again outside it: by another
// solver, in a benchmark, in a test. Every number is written with "%.17g",
// so a saved problem loads back bit for bit.
//
// Each file is a list of lines "KEYWORD value ...", one record a line; blank
// lines and lines starting with '#' are skipped. A 3×3 information matrix is
// its 9 entries row by row, a 2×2 one its 4; a pose is "x y theta" (m, m,
// rad). Kernels are "none", "huber" or "cauchy".
//
// Pose graph (PoseGraph with the PoseGraphOptions it is solved with):
//   POSE_GRAPH_OPTIONS max_iterations convergence_step robust_kernel_width initial_lambda
//   NODE index x y theta                      (indices 0, 1, 2, … in order; node 0 is fixed)
//   EDGE from to x y theta I00 … I22 robust active   (robust, active: 0 or 1)
//
// Landmark graph (LandmarkGraph with its LandmarkGraphOptions):
//   LANDMARK_GRAPH_OPTIONS max_iterations convergence_step min_relative_decrease
//                          initial_lambda kernel_width
//   LASER x y theta                           (base_link → laser, for every observation)
//   POSE index x y theta fixed                (fixed: 0 or 1)
//   LANDMARK index x y
//   RELATIVE from to from_offset(3) to_offset(3) measurement(3) I00 … I22 kernel
//   PRIOR pose mean(3) I00 … I22
//   OBSERVATION pose landmark range bearing I00 I01 I10 I11 kernel
//
// Scan anchors: how each scan of a run hangs off a graph node, to turn a
// solution (node poses) into a trajectory with one pose per scan:
//   SCAN stamp node x y theta
// the scan's pose is node ⊕ (x, y, theta); node −1: (x, y, theta) is the
// scan's pose itself (a scan before the first node).
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/pose_graph/landmark_graph.h"
#include "ekf_slam_core/pose_graph/pose_graph.h"

namespace ekf_slam {

// Each returns an empty string on success, else "<path>: <problem>" or
// "<path>:<line>: <problem>". A load replaces the outputs only on success.
std::string savePoseGraph(const std::string& path, const PoseGraph& graph,
                          const PoseGraphOptions& options);
std::string loadPoseGraph(const std::string& path, PoseGraph* graph, PoseGraphOptions* options);

std::string saveLandmarkGraph(const std::string& path, const LandmarkGraph& graph,
                              const LandmarkGraphOptions& options);
std::string loadLandmarkGraph(const std::string& path, LandmarkGraph* graph,
                              LandmarkGraphOptions* options);

struct ScanAnchor {
  double stamp = 0.0;  // s
  int node = -1;       // graph node the scan hangs off, −1: none
  Pose2 offset;        // the scan in the node's frame (node −1: the scan's pose)
};

std::string saveScanAnchors(const std::string& path, const std::vector<ScanAnchor>& anchors);
std::string loadScanAnchors(const std::string& path, std::vector<ScanAnchor>* anchors);

// One pose per anchor: node_poses[node] ⊕ offset (the offset alone for node
// −1 or a node beyond node_poses).
std::vector<StampedPose> anchoredScanPoses(const std::vector<ScanAnchor>& anchors,
                                           const std::vector<Pose2>& node_poses);

}  // namespace ekf_slam
