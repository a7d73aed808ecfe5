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

DampedStep levenbergMarquardtStep(const Eigen::SparseMatrix<double>& H,
                                  const Eigen::VectorXd& gradient, double initial_lambda,
                                  double* lambda,
                                  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>* solver,
                                  const std::function<bool(const Eigen::VectorXd&)>& take) {
  DampedStep result;
  const Eigen::VectorXd diagonal = H.diagonal();
  for (int attempt = 0; attempt < 10 && !result.improved; ++attempt) {
    Eigen::SparseMatrix<double> damped = H;
    for (int k = 0; k < H.rows(); ++k) {
      damped.coeffRef(k, k) += *lambda * diagonal(k) + (diagonal(k) > 0.0 ? 0.0 : 1.0);
    }
    solver->factorize(damped);
    if (solver->info() != Eigen::Success) {
      *lambda = std::max(1e-6, *lambda * 10.0);
      continue;
    }
    const Eigen::VectorXd step = solver->solve(-gradient);
    if (!step.allFinite()) break;
    if (take(step)) {
      result.improved = true;
      result.largest_step = step.cwiseAbs().maxCoeff();
      *lambda = std::max(initial_lambda, *lambda * 0.1);
    } else {
      *lambda = std::max(1e-6, *lambda * 10.0);
    }
  }
  return result;
}

}  // namespace ekf_slam
