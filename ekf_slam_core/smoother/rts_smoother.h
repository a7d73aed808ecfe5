// Rauch–Tung–Striebel smoothing of the robot trajectory from stored filter
// quantities (thesis §3.4.5.1, eq. 3.62–3.66), so that every scan can be
// re-projected from an improved pose into a complete metric map.
//
// For each filter step k the forward run stores the filtered pose x_k|k and
// its covariance P_k|k, the motion Jacobian F_k of the step k → k+1, and the
// prediction x_k+1|k, P_k+1|k. The backward pass, from the last step down:
//   C_k   = P_k|k F_kᵀ P_k+1|k⁻¹
//   x^s_k = x_k|k + C_k (x^s_k+1 − x_k+1|k)                (angle wrapped)
//   P^s_k = P_k|k + C_k (P^s_k+1 − P_k+1|k) C_kᵀ
// The thesis prints P^s_k = (I − K F_k) P_k|k (eq. 3.66), which ignores the
// smoothed covariance of the next step; the form above is the RTS one.
//
// In EKF-SLAM the pose marginal is not exactly Markov once landmarks tie
// poses together; like the thesis, this smoother treats it as such. It is
// exact for a linear-Gaussian chain (tested).
#pragma once

#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

struct SmootherStep {
  double stamp = 0.0;    // s, of the scan this estimate belongs to
  Pose2 filtered;        // x_k|k
  Matrix3 filtered_cov;  // P_k|k
  // The transition to the next step (unused on the last step):
  Matrix3 F_next = Matrix3::Identity();          // F_k
  Pose2 predicted_next;                          // x_k+1|k
  Matrix3 predicted_next_cov = Matrix3::Zero();  // P_k+1|k
};

struct SmoothedPose {
  double stamp = 0.0;
  Pose2 pose;
  Matrix3 covariance;
};

// Records the forward run. Call addFiltered() after each step's update, and
// addTransition() with each prediction (before the next addFiltered()).
class TrajectoryRecorder {
 public:
  void addTransition(const Matrix3& F, const Pose2& predicted, const Matrix3& predicted_cov);
  void addFiltered(double stamp, const Pose2& pose, const Matrix3& covariance);
  // Replaces the last filtered estimate (the update after the prediction).
  const std::vector<SmootherStep>& steps() const { return steps_; }
  void clear() { steps_.clear(); }
  // Goes on from steps recorded earlier (a resumed run).
  void restore(std::vector<SmootherStep> steps) { steps_ = std::move(steps); }
  // Forgets the oldest `count` steps (a bounded history): the chain then
  // starts at the step that was number `count`.
  void dropFront(size_t count);

 private:
  std::vector<SmootherStep> steps_;
};

// Backward RTS pass. A step whose P_k+1|k is not invertible keeps its
// filtered estimate (nothing is propagated through it).
std::vector<SmoothedPose> smoothTrajectory(const std::vector<SmootherStep>& steps);

}  // namespace ekf_slam
