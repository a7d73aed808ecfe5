#include "ekf_slam_core/smoother/rts_smoother.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>

namespace ekf_slam {

void TrajectoryRecorder::addTransition(const Matrix3& F, const Pose2& predicted,
                                       const Matrix3& predicted_cov) {
  if (steps_.empty()) return;  // nothing to transition from
  SmootherStep& last = steps_.back();
  // Several predictions between two recorded estimates compose: the chained
  // Jacobian is F₂F₁ and the last prediction is the one to compare with.
  last.F_next = F * last.F_next;
  last.predicted_next = predicted;
  last.predicted_next_cov = predicted_cov;
}

void TrajectoryRecorder::addFiltered(double stamp, const Pose2& pose, const Matrix3& covariance) {
  SmootherStep step;
  step.stamp = stamp;
  step.filtered = pose;
  step.filtered_cov = covariance;
  steps_.push_back(step);
}

void TrajectoryRecorder::dropFront(size_t count) {
  steps_.erase(steps_.begin(), steps_.begin() + std::min(count, steps_.size()));
}

std::vector<SmoothedPose> smoothTrajectory(const std::vector<SmootherStep>& steps) {
  std::vector<SmoothedPose> out(steps.size());
  if (steps.empty()) return out;
  const size_t last = steps.size() - 1;
  out[last] = {steps[last].stamp, steps[last].filtered, steps[last].filtered_cov};
  for (size_t i = last; i-- > 0;) {
    const SmootherStep& s = steps[i];
    out[i] = {s.stamp, s.filtered, s.filtered_cov};
    const Eigen::LDLT<Matrix3> predicted(s.predicted_next_cov);
    if (predicted.info() != Eigen::Success || !(predicted.vectorD().minCoeff() > 1e-18)) {
      continue;  // no information to carry back through this step
    }
    // C = P F' P_pred⁻¹  ⇔  Cᵀ = P_pred⁻¹ F P (P symmetric).
    const Matrix3 C = predicted.solve(s.F_next * s.filtered_cov).transpose();
    Vector3 correction = out[i + 1].pose.vector() - s.predicted_next.vector();
    correction(2) = wrapAngle(correction(2));
    out[i].pose = Pose2::fromVector(s.filtered.vector() + C * correction);
    const Matrix3 cov =
        s.filtered_cov + C * (out[i + 1].covariance - s.predicted_next_cov) * C.transpose();
    out[i].covariance = 0.5 * (cov + cov.transpose());
  }
  return out;
}

}  // namespace ekf_slam
