// Sparse nonlinear least squares over robot poses and point landmarks: the
// batch (GraphSLAM) form of what the EKF estimates recursively. PoseGraph's
// sibling, with landmark nodes and range–bearing edges added.
//
// Maths, in the code's symbols (derivation in docs/maths.md §8). Unknowns:
// poses x_i = (x, y, θ) and landmarks m_j = (x, y), both in the map frame;
// poses may be held fixed (the gauge). Edges and their errors:
//   relative pose   e = between(z, between(x_a ⊕ o_a, x_b ⊕ o_b))      (3)
//                   o_a, o_b constant offsets (a key scan hanging off an
//                   iteration pose); identity for a motion edge;
//   pose prior      e = (x − μ) with the heading wrapped                 (3)
//   observation     e = (r − r̂, wrap(φ − φ̂)),  (r̂, φ̂) = h(x_i, m_j)       (2)
//                   h through the laser mount (models/point_observation_model.h);
//                   J_e_x = −H_r, J_e_m = −H_m.
// Cost Σ ρ(eᵀ Ω e): ρ(s) = s for trusted edges, a Huber or Cauchy kernel on
// the ones marked robust, handled by iteratively reweighted least squares
// (weight ρ'(s) frozen per step). Each Levenberg–Marquardt step solves
//   (Σ w Jᵀ Ω J + λ diag) δ = −Σ w Jᵀ Ω e
// with a sparse LDLᵀ (Eigen, AMD ordering), is kept only when the robust
// cost does not increase, and λ follows the gain ratio (levenberg_marquardt.h).
// A solve ends when the largest step component or the relative decrease
// falls below its tolerance.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/models/point_observation_model.h"
#include "ekf_slam_core/pose_graph/levenberg_marquardt.h"

namespace ekf_slam {

struct RelativePoseEdge {
  int from = 0;
  int to = 0;
  Pose2 from_offset;  // constant right factor on x_from (identity: the node itself)
  Pose2 to_offset;
  Pose2 measurement;  // pose of (to ⊕ to_offset) in the frame of (from ⊕ from_offset)
  Matrix3 information = Matrix3::Identity();
  RobustKernel kernel = RobustKernel::kNone;
};

struct PosePriorEdge {
  int pose = 0;
  Pose2 mean;
  Matrix3 information = Matrix3::Identity();
};

struct ObservationEdge {
  int pose = 0;
  int landmark = 0;
  RangeBearing z;
  Matrix2 information = Matrix2::Identity();  // inverse of the (range, bearing) covariance
  RobustKernel kernel = RobustKernel::kNone;
};

struct LandmarkGraphOptions {
  int max_iterations = 100;        // Levenberg–Marquardt steps
  double convergence_step = 1e-6;  // m or rad: a smaller largest step component ends it
  // A step that lowers the cost by less than this fraction ends it too.
  double min_relative_decrease = 1e-7;
  double initial_lambda = 1e-6;  // damping at the first step (relative to the diagonal)
  double kernel_width = 3.0;     // sigmas, for every robust edge

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("kernel_width", kernel_width, Bounds::openClosed(0.0, 1000.0, "sigmas"));
    v.integer("max_iterations", max_iterations, Bounds::closed(1, 100000));
    v.number("min_relative_decrease", min_relative_decrease, Bounds::closed(0.0, 1.0));
    v.number("convergence_step", convergence_step, Bounds::openClosed(0.0, 1.0, "m or rad"));
    v.number("initial_lambda", initial_lambda, Bounds::closed(0.0, 1e6));
  }

  std::string validate() const;  // empty when valid, else names the bad field
};

struct LandmarkGraphSummary {
  int iterations = 0;
  // Orderings and symbolic factorisations of H: one per optimisation, and
  // one more each time an edge drops out or comes back.
  int symbolic_analyses = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  SolveEnd end = SolveEnd::kIterationLimit;
  bool converged() const { return end == SolveEnd::kConverged; }
};

// Edge errors with optional Jacobians (additive (x, y, θ) / (x, y) convention).
Vector3 relativePoseError(const Pose2& from, const Pose2& to, const RelativePoseEdge& edge,
                          Matrix3* J_e_from = nullptr, Matrix3* J_e_to = nullptr);
// False (outputs untouched) when the landmark sits at the sensor origin.
bool observationError(const Pose2& robot, const Pose2& laser, const Vector2& landmark,
                      const RangeBearing& z, Vector2* e, Matrix23* J_e_robot = nullptr,
                      Matrix2* J_e_landmark = nullptr);

class LandmarkGraph {
 public:
  // All observation edges share one laser mount (base_link → laser).
  explicit LandmarkGraph(const Pose2& laser_pose = Pose2()) : laser_(laser_pose) {}

  int addPose(const Pose2& pose, bool fixed = false);
  int addLandmark(const Vector2& position);
  void addEdge(const RelativePoseEdge& edge);
  void addEdge(const PosePriorEdge& edge);
  void addEdge(const ObservationEdge& edge);

  int poseCount() const { return static_cast<int>(poses_.size()); }
  int landmarkCount() const { return static_cast<int>(landmarks_.size()); }
  const std::vector<Pose2>& poses() const { return poses_; }
  const std::vector<Vector2>& landmarks() const { return landmarks_; }
  const std::vector<ObservationEdge>& observationEdges() const { return observations_; }
  // The rest of the problem as given (for saving it: graph_io.h).
  const Pose2& laserPose() const { return laser_; }
  bool isFixed(int pose) const { return fixed_[pose] != 0; }
  const std::vector<RelativePoseEdge>& relativeEdges() const { return relatives_; }
  const std::vector<PosePriorEdge>& priorEdges() const { return priors_; }

  // Robust cost at the current estimate.
  double cost(double kernel_width) const;
  // Squared Mahalanobis error of an observation edge (0 when undefined).
  double observationChi2(int edge) const;

  LandmarkGraphSummary optimize(const LandmarkGraphOptions& options);

 private:
  double cost(const std::vector<Pose2>& poses, const std::vector<Vector2>& landmarks,
              double kernel_width) const;

  Pose2 laser_;
  std::vector<Pose2> poses_;
  std::vector<char> fixed_;
  std::vector<Vector2> landmarks_;
  std::vector<RelativePoseEdge> relatives_;
  std::vector<PosePriorEdge> priors_;
  std::vector<ObservationEdge> observations_;
};

}  // namespace ekf_slam
