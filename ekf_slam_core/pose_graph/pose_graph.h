// 2D pose-graph optimisation: the back end that can move past poses when a
// loop closes, which the EKF (current pose only) cannot.
//
// Maths, in the code's symbols. Nodes are poses x_i = (x, y, θ) in the map
// frame; node 0 is held fixed (it defines the map frame). An edge (i, j)
// measures z, the pose of j in i's frame, with information Ω. Its error is
// the pose that remains between the prediction and the measurement,
//   e_ij = vec(z ⊖ (x_i ⊖ x_j))   i.e. between(z, between(x_i, x_j)),
// zero when x_j = x_i ⊕ z, with the Jacobians chained from pose2.h's
//   J_e_xi = J_e_r · J_r_xi,  J_e_xj = J_e_r · J_r_xj,  r = between(x_i, x_j).
// The cost is Σ ρ(e_ijᵀ Ω e_ij) with ρ(s) = s for trusted edges (the
// sequential ones) and the Cauchy kernel ρ(s) = c² log(1 + s / c²) for
// loop closures, so a false loop whose error stays large after the
// optimisation is down-weighted by w = ρ'(s) = 1 / (1 + s / c²) instead of
// bending the map (iteratively reweighted least squares). Each
// Levenberg-Marquardt step solves the sparse normal equations
//   (H + λ diag(H)) δ = −Σ w Jᵀ Ω e,   H = Σ w Jᵀ Ω J
// (Marquardt's scaling: each unknown is damped relative to its own
// curvature) with a simplicial LDLᵀ factorisation (Eigen), is kept only
// when the robust cost does not rise, and λ follows the gain ratio
// (levenberg_marquardt.h).
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/pose_graph/levenberg_marquardt.h"

namespace ekf_slam {

struct PoseGraphEdge {
  int from = 0;
  int to = 0;
  Pose2 measurement;                          // pose of `to` in the frame of `from`
  Matrix3 information = Matrix3::Identity();  // inverse covariance of the measurement
  bool robust = false;                        // Cauchy kernel (loop closures)
  bool active = true;                         // inactive edges are ignored
};

struct PoseGraphOptions {
  int max_iterations = 20;         // Levenberg-Marquardt steps per optimize()
  double convergence_step = 1e-6;  // m or rad: a smaller largest step component ends it
  double robust_kernel_width =
      3.0;                       // c: Mahalanobis distance (sigmas) where the Cauchy weight is 1/2
  double initial_lambda = 1e-6;  // LM damping at the first step (relative to the diagonal)

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.integer("max_iterations", max_iterations, Bounds::closed(1, 10000));
    v.number("convergence_step", convergence_step, Bounds::openClosed(0.0, 1.0, "m or rad"));
    v.number("robust_kernel_width", robust_kernel_width, Bounds::openClosed(0.0, 1000.0, "sigmas"));
    v.number("initial_lambda", initial_lambda, Bounds::closed(0.0, 1e6));
  }

  std::string validate() const;  // empty when valid, else names the bad field
};

struct PoseGraphSummary {
  int iterations = 0;
  double initial_cost = 0.0;  // robust cost before and after
  double final_cost = 0.0;
  SolveEnd end = SolveEnd::kIterationLimit;
  bool converged() const { return end == SolveEnd::kConverged; }
};

// The error of one edge at the given poses, with optional Jacobians (3×3
// each, this library's additive (x, y, θ) convention).
Vector3 edgeError(const Pose2& from, const Pose2& to, const Pose2& measurement,
                  Matrix3* J_e_from = nullptr, Matrix3* J_e_to = nullptr);

class PoseGraph {
 public:
  int addNode(const Pose2& pose);  // returns its index
  // Returns the edge's index. Both nodes must exist.
  int addEdge(const PoseGraphEdge& edge);

  int nodeCount() const { return static_cast<int>(poses_.size()); }
  const std::vector<Pose2>& poses() const { return poses_; }
  const Pose2& pose(int node) const { return poses_[node]; }
  void setPose(int node, const Pose2& pose) { poses_[node] = pose; }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  void setEdgeActive(int edge, bool active) { edges_[edge].active = active; }
  void setEdgeRobust(int edge, bool robust) { edges_[edge].robust = robust; }

  // Squared Mahalanobis error eᵀ Ω e of an edge at the current poses.
  double edgeChi2(int edge) const;
  // Its kernel weight (1 for a non-robust edge).
  double edgeWeight(int edge, double robust_kernel_width) const;

  // Moves every node but node 0 to minimise the robust cost.
  PoseGraphSummary optimize(const PoseGraphOptions& options);

 private:
  double cost(const std::vector<Pose2>& poses, double kernel_width) const;

  std::vector<Pose2> poses_;
  std::vector<PoseGraphEdge> edges_;
};

}  // namespace ekf_slam
