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

// The damping carried from one step to the next: λ, relative to diag(H),
// and ν, the factor of the next raise.
struct Damping {
  explicit Damping(double initial_lambda) : lambda(initial_lambda) {}
  double lambda;
  double raise = 2.0;
};

struct DampedStep {
  bool improved = false;      // a step that does not raise the cost was taken
  double largest_step = 0.0;  // its largest component
  double cost = 0.0;          // the cost after it (the old cost when none was taken)
  // No step was taken, and the undamped model predicts a decrease below
  // the cost's rounding (10⁻¹² of it): the estimate is at the minimum.
  bool at_minimum = false;
};

// One step of Levenberg–Marquardt on the cost F = Σ ρ(eᵀ Ω e) at cost `cost`,
// with H = Σ w Jᵀ Ω J (lower triangle) and gradient = Σ w Jᵀ Ω e, w = ρ'(s):
// solves (H + λ D) δ = −gradient, D = diag(H), and hands δ to `trial`, which
// forms the candidate x ⊞ δ, keeps it and returns F there. A candidate that
// does not raise the cost is the step; the caller then applies the candidate
// it kept last. The model F(x ⊞ δ) ≈ F + 2 gᵀδ + δᵀHδ predicts the decrease
// −gᵀδ + λ δᵀDδ, and the gain ratio ϱ = actual / predicted sets the next λ
// (Nielsen's schedule, as a trust region does): λ × max(⅓, 1 − (2ϱ − 1)³)
// after a step, so λ falls where the model holds and stays where it does
// not; λ × ν, ν × 2 after each refused candidate, ten at most. An unknown
// no edge touches (zero diagonal) gets a unit diagonal so the system stays
// regular. `solver` must have analysed H's pattern.
DampedStep levenbergMarquardtStep(const Eigen::SparseMatrix<double>& H,
                                  const Eigen::VectorXd& gradient, double cost, Damping* damping,
                                  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>* solver,
                                  const std::function<double(const Eigen::VectorXd&)>& trial);

// Why a solve ended.
enum class SolveEnd {
  kConverged,       // the step or the relative decrease fell below its
                    // tolerance, or the model predicts no decrease
  kStalled,         // no damping gave a step that does not raise the cost,
                    // away from the minimum
  kIterationLimit,  // max_iterations steps were taken
};
const char* solveEndName(SolveEnd end);

}  // namespace ekf_slam
