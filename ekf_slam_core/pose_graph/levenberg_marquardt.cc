#include "ekf_slam_core/pose_graph/levenberg_marquardt.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {

double robustCost(RobustKernel kernel, double s, double c) {
  switch (kernel) {
    case RobustKernel::kNone:
      return s;
    case RobustKernel::kHuber: {
      const double r = std::sqrt(s);
      return r <= c ? s : 2.0 * c * r - c * c;
    }
    case RobustKernel::kCauchy:
      return c * c * std::log1p(s / (c * c));
  }
  return s;
}

double robustWeight(RobustKernel kernel, double s, double c) {
  switch (kernel) {
    case RobustKernel::kNone:
      return 1.0;
    case RobustKernel::kHuber: {
      const double r = std::sqrt(s);
      return r <= c ? 1.0 : c / r;
    }
    case RobustKernel::kCauchy:
      return 1.0 / (1.0 + s / (c * c));
  }
  return 1.0;
}

const char* solveEndName(SolveEnd end) {
  switch (end) {
    case SolveEnd::kConverged:
      return "converged";
    case SolveEnd::kStalled:
      return "stalled";
    case SolveEnd::kIterationLimit:
      return "iteration limit";
  }
  return "?";
}

namespace {

// λ stays within these: below, the step is Gauss–Newton's to rounding;
// above, it is a vanishing gradient step.
constexpr double kMinLambda = 1e-12;
constexpr double kMaxLambda = 1e12;
constexpr int kTries = 10;
// A decrease below this fraction of the cost is lost in the rounding of a
// sum of many terms: a model that predicts no more stands at the minimum.
constexpr double kRounding = 1e-12;

}  // namespace

DampedStep levenbergMarquardtStep(const Eigen::SparseMatrix<double>& H,
                                  const Eigen::VectorXd& gradient, double cost, Damping* damping,
                                  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>* solver,
                                  const std::function<double(const Eigen::VectorXd&)>& trial) {
  DampedStep result;
  result.cost = cost;
  const Eigen::VectorXd diagonal = H.diagonal();
  auto refuse = [&] {
    damping->lambda = std::min(kMaxLambda, damping->lambda * damping->raise);
    damping->raise *= 2.0;
  };
  for (int attempt = 0; attempt < kTries; ++attempt) {
    // What the damping adds to H: λ D, and 1 where H's diagonal is empty.
    Eigen::VectorXd added(H.rows());
    for (int k = 0; k < H.rows(); ++k) {
      added(k) = diagonal(k) > 0.0 ? damping->lambda * diagonal(k) : 1.0;
    }
    Eigen::SparseMatrix<double> damped = H;
    for (int k = 0; k < H.rows(); ++k) damped.coeffRef(k, k) += added(k);
    solver->factorize(damped);
    if (solver->info() != Eigen::Success) {
      refuse();
      continue;
    }
    const Eigen::VectorXd step = solver->solve(-gradient);
    if (!step.allFinite()) break;
    // (H + λD) δ = −g gives δᵀHδ = −gᵀδ − δᵀ(λD)δ, so the model's decrease
    // −(2gᵀδ + δᵀHδ) is −gᵀδ + δᵀ(λD)δ.
    const double predicted = -gradient.dot(step) + step.dot(added.cwiseProduct(step));
    if (attempt == 0) result.at_minimum = predicted <= kRounding * std::abs(cost);
    const double new_cost = trial(step);
    if (!(new_cost <= cost)) {  // a NaN cost is refused too
      refuse();
      continue;
    }
    const double gain = predicted > 0.0 ? (cost - new_cost) / predicted : 0.0;
    const double shrink = std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * gain - 1.0, 3));
    damping->lambda = std::clamp(damping->lambda * shrink, kMinLambda, kMaxLambda);
    damping->raise = 2.0;
    result.improved = true;
    result.at_minimum = false;
    result.largest_step = step.cwiseAbs().maxCoeff();
    result.cost = new_cost;
    break;
  }
  return result;
}

}  // namespace ekf_slam
