// Range–bearing observation of a point landmark (thesis §3.2.2, §4.2.1),
// with the laser mounted at a pose `laser` in the robot frame (base_link →
// laser, from calibration).
//
// With the sensor pose s = x_r ⊕ laser and the landmark m in the map frame:
//   l = Rᵀ(s_θ)(m − s_t)                      (landmark in the laser frame)
//   z = h(x_r, m) = (r, φ) = (|l|, atan2(l_y, l_x))
// The thesis's printed eq. 3.13 has the difference reversed (robot − feature)
// inside atan2; the model above is the corrected one.
//
// Jacobians (chain rule through compose and transformTo):
//   ∂z/∂l = [l_x/r  l_y/r; −l_y/r²  l_x/r²]
//   H_r = ∂z/∂l · ∂l/∂s · ∂s/∂x_r,   H_m = ∂z/∂l · Rᵀ(s_θ)
// Inverse model for augmentation (§4.2.4): m = g(x_r, z) = s_t + R(s_θ)(r cos φ, r sin φ)
// with Jacobians G_r = ∂m/∂x_r and G_z = ∂m/∂z.
#pragma once

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

struct RangeBearing {
  double range = 0.0;    // m
  double bearing = 0.0;  // rad, in the laser frame, counter-clockwise from its x axis

  Vector2 vector() const { return Vector2(range, bearing); }
};

// Predicted observation of landmark `m` from robot pose `robot`. Returns
// false (outputs untouched) when the landmark is at the sensor origin, where
// the bearing is undefined.
bool predictPointObservation(const Pose2& robot, const Pose2& laser, const Vector2& m,
                             RangeBearing* z, Matrix23* H_robot = nullptr,
                             Matrix2* H_landmark = nullptr);

// Landmark position in the map frame from an observation (inverse model).
Vector2 landmarkFromObservation(const Pose2& robot, const Pose2& laser, const RangeBearing& z,
                                Matrix23* G_robot = nullptr, Matrix2* G_z = nullptr);

}  // namespace ekf_slam
