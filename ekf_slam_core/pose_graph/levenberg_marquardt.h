// The damped step both sparse optimisers of this folder take (PoseGraph over
// poses, LandmarkGraph over poses and point landmarks): one place for the
// Levenberg–Marquardt damping schedule and the robust kernels.
#pragma once

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <functional>

namespace ekf_slam {

enum class RobustKernel { kNone, kHuber, kCauchy };

// ρ(s) and its weight ρ'(s) for s = eᵀ Ω e, width c in sigmas (√s where the
// kernel leaves the quadratic: Huber) or where the weight is ½ (Cauchy).
double robustCost(RobustKernel kernel, double s, double c);
double robustWeight(RobustKernel kernel, double s, double c);

struct DampedStep {
  bool improved = false;      // a step lowered the cost and was taken
  double largest_step = 0.0;  // its largest component
};

// Solves (H + λ diag(H)) δ = −g for growing λ (×10, up to 10 tries) until
// `take(δ)` accepts δ (it applies δ when it lowers the cost and returns
// true); then λ shrinks (×0.1, not below initial_lambda). An unknown no
// edge touches (zero diagonal) gets a unit diagonal so the system stays
// regular. `solver` must have analysed H's pattern.
DampedStep levenbergMarquardtStep(const Eigen::SparseMatrix<double>& H,
                                  const Eigen::VectorXd& gradient, double initial_lambda,
                                  double* lambda,
                                  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>* solver,
                                  const std::function<bool(const Eigen::VectorXd&)>& take);

}  // namespace ekf_slam
