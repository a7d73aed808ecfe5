// Ceres as the reference the hand-written Levenberg–Marquardt is checked
// against (the gtests of pose_graph/, tools/dev/solver_comparison.sh); the
// pipeline does not use it. The pose graph's and the full smoother's
// residuals as Ceres cost functions: the errors and Jacobians are
// pose_graph/'s own (edgeError,
// relativePoseError, observationError), whitened by S with Sᵀ S = Ω, so
// that Ceres's ½ Σ ρ(‖S e‖²) is half the hand-written cost Σ ρ(eᵀ Ω e)
// term for term (Ceres's CauchyLoss(c) and HuberLoss(c) are the ρ of
// levenberg_marquardt.h with the same c). Headings are plain parameters,
// wrapped inside the errors as the hand-written solver does.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <array>
#include <vector>

#include "ekf_slam_core/pose_graph/landmark_graph.h"
#include "ekf_slam_core/pose_graph/pose_graph.h"

namespace ekf_slam {
namespace ceres_costs {

// S with Sᵀ S = Ω (the symmetric part: eᵀ Ω e only sees that), S = D^½ Vᵀ
// from the eigen-decomposition, so that a semi-definite Ω (a heading edge
// informs the heading alone: diag(0, 0, w)) has its root too, where a
// Cholesky factor would stop at the first zero pivot.
template <int N>
Eigen::Matrix<double, N, N> squareRootInformation(const Eigen::Matrix<double, N, N>& omega) {
  const Eigen::Matrix<double, N, N> symmetric = 0.5 * (omega + omega.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(symmetric);
  const Eigen::Matrix<double, N, 1> root = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return root.asDiagonal() * eigen.eigenvectors().transpose();
}

inline Pose2 poseOf(const double* p) { return Pose2(p[0], p[1], p[2]); }

// A relative-pose edge; PoseGraph's when `plain` is set (edgeError itself,
// the offsets of the RelativePoseEdge unused).
class RelativePoseCost : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  RelativePoseCost(const RelativePoseEdge& edge, bool plain)
      : edge_(edge), plain_(plain), sqrt_information_(squareRootInformation<3>(edge.information)) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Matrix3 J_from, J_to;
    const Pose2 from = poseOf(parameters[0]), to = poseOf(parameters[1]);
    const Vector3 e = plain_ ? edgeError(from, to, edge_.measurement, &J_from, &J_to)
                             : relativePoseError(from, to, edge_, &J_from, &J_to);
    Eigen::Map<Vector3>{residuals} = sqrt_information_ * e;
    using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    if (jacobians && jacobians[0]) Eigen::Map<RowMajor3>{jacobians[0]} = sqrt_information_ * J_from;
    if (jacobians && jacobians[1]) Eigen::Map<RowMajor3>{jacobians[1]} = sqrt_information_ * J_to;
    return true;
  }

 private:
  RelativePoseEdge edge_;
  bool plain_;
  Matrix3 sqrt_information_;
};

class PosePriorCost : public ceres::SizedCostFunction<3, 3> {
 public:
  explicit PosePriorCost(const PosePriorEdge& edge)
      : mean_(edge.mean), sqrt_information_(squareRootInformation<3>(edge.information)) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Vector3 e = poseOf(parameters[0]).vector() - mean_.vector();
    e(2) = wrapAngle(e(2));
    Eigen::Map<Vector3>{residuals} = sqrt_information_ * e;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>{jacobians[0]} = sqrt_information_;
    }
    return true;
  }

 private:
  Pose2 mean_;
  Matrix3 sqrt_information_;
};

// A landmark at the sensor origin has no bearing: the hand-written cost
// leaves such a term out, here it is a zero residual.
class ObservationCost : public ceres::SizedCostFunction<2, 3, 2> {
 public:
  ObservationCost(const ObservationEdge& edge, const Pose2& laser)
      : z_(edge.z), laser_(laser), sqrt_information_(squareRootInformation<2>(edge.information)) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Vector2 e = Vector2::Zero();
    Matrix23 J_robot = Matrix23::Zero();
    Matrix2 J_landmark = Matrix2::Zero();
    observationError(poseOf(parameters[0]), laser_, Vector2(parameters[1][0], parameters[1][1]), z_,
                     &e, &J_robot, &J_landmark);
    Eigen::Map<Vector2>{residuals} = sqrt_information_ * e;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>>{jacobians[0]} =
          sqrt_information_ * J_robot;
    }
    if (jacobians && jacobians[1]) {
      Eigen::Map<Eigen::Matrix<double, 2, 2, Eigen::RowMajor>>{jacobians[1]} =
          sqrt_information_ * J_landmark;
    }
    return true;
  }

 private:
  RangeBearing z_;
  Pose2 laser_;
  Matrix2 sqrt_information_;
};

// The kernel of a robust edge; the problem takes ownership of nothing:
// the loss functions live as long as the Kernels (pass
// Problem::Options::loss_function_ownership = DO_NOT_TAKE_OWNERSHIP).
struct Kernels {
  explicit Kernels(double c) : cauchy(c), huber(c) {}
  ceres::LossFunction* of(RobustKernel kernel) {
    switch (kernel) {
      case RobustKernel::kNone:
        return nullptr;
      case RobustKernel::kHuber:
        return &huber;
      case RobustKernel::kCauchy:
        return &cauchy;
    }
    return nullptr;
  }
  ceres::CauchyLoss cauchy;
  ceres::HuberLoss huber;
};

// The problems, built once for the reference solves below and the solver
// comparison alike. Each unknown is an array (pose: x, y, θ; landmark: x, y)
// the caller fills with the start and reads back; loss functions come from
// `kernels` (the problem must not own them: DO_NOT_TAKE_OWNERSHIP).
// The graph's values as those arrays.
std::vector<std::array<double, 3>> poseArrays(const std::vector<Pose2>& poses);
std::vector<std::array<double, 2>> landmarkArrays(const std::vector<Vector2>& landmarks);
// Every active edge of `graph`; node 0 held constant.
void addPoseGraph(const PoseGraph& graph, Kernels* kernels,
                  std::vector<std::array<double, 3>>* poses, ceres::Problem* problem);
// Every edge of `graph`; its fixed poses held constant.
void addLandmarkGraph(const LandmarkGraph& graph, Kernels* kernels,
                      std::vector<std::array<double, 3>>* poses,
                      std::vector<std::array<double, 2>>* landmarks, ceres::Problem* problem);

}  // namespace ceres_costs

// Ceres's Levenberg–Marquardt (sparse Cholesky of the normal equations, one
// thread, the same first damping) from the graph's current values, until a
// step lowers the cost by less than `function_tolerance` of it. Returns the
// solved graph; its summary's costs are the hand-written Σ ρ(eᵀ Ω e).
PoseGraph solveWithCeres(const PoseGraph& graph, const PoseGraphOptions& options,
                         double function_tolerance, PoseGraphSummary* summary = nullptr);
LandmarkGraph solveWithCeres(const LandmarkGraph& graph, const LandmarkGraphOptions& options,
                             LandmarkGraphSummary* summary = nullptr);
// The same problem with other values.
LandmarkGraph withValues(const LandmarkGraph& graph, const std::vector<Pose2>& poses,
                         const std::vector<Vector2>& landmarks);

}  // namespace ekf_slam
