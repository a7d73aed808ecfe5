// Line landmarks (thesis §4.3): observation and inverse models, maths only.
//
// A line is kept in the normal form x cos θ + y sin θ = p (PolarLine): θ is
// the direction of the normal from the frame's origin towards the line, p its
// distance. Every output is normalised to p >= 0, θ in [-π, π); inputs need
// not be (the formulas hold for a signed p, and (p, θ) ≡ (−p, θ + π)). The
// laser sits at `laser` in the robot frame (base_link → laser), as in
// point_observation_model.h. Symbols:
//   x_r = (x, y, θ_r) robot pose, s = x_r ⊕ laser = (s_t, s_θ) sensor pose,
//   n(α) = (cos α, sin α), n⊥(α) = (−sin α, cos α), wrap = wrapAngle.
//   ∂s/∂x_r = [I₂  R'(θ_r) L_t; 0 0 1] (compose), so ∂s_t/∂θ_r = R'(θ_r) L_t.
//
// (a) Full (p, θ) landmark in the map frame, ℓ = (ρ, α).
//   A map point q = s_t + R(s_θ) l lies on ℓ iff n(α)·s_t + n(α − s_θ)·l = ρ,
//   so in the laser frame
//     p' = ρ − n(α)·s_t,   θ' = α − s_θ,
//   and when p' < 0 (the sensor is on the far side of ℓ from the map origin)
//   z = (−p', wrap(θ' + π)), else z = (p', wrap(θ')). With σ = sign (+1 at
//   p' = 0, where |p'| has no derivative):
//     ∂p'/∂ρ = 1, ∂p'/∂α = −n⊥(α)·s_t, ∂p'/∂s_t = −n(α)ᵀ, ∂p'/∂s_θ = 0
//     ∂θ'/∂α = 1, ∂θ'/∂s_θ = −1
//     H_landmark = [σ  −σ n⊥(α)·s_t; 0  1]
//     H_robot    = [−σ n(α)ᵀ   −σ n(α)·R'(θ_r)L_t;  0 0 −1]
//   The flip negates the p row only (θ + π is a constant shift).
//   Inverse (augmentation): α' = θ + s_θ, ρ' = p + n(α')·s_t, normalised the
//   same way (τ = sign of ρ'):
//     G_z     = [τ  τ n⊥(α')·s_t; 0  1]
//     G_robot = [τ n(α')ᵀ   τ (n(α')·R'(θ_r)L_t + n⊥(α')·s_t);  0 0 1]
//   The thesis's eq. 4.26 has the p row with the opposite sign (it gives −p
//   for a robot at the origin), no mount and no side handling.
//
// (b) θ-only line landmark (the thesis's final choice, §4.3.3): the state
//   holds θ_f, the map-frame normal direction; the offset of the line comes
//   from endpoint point landmarks in the state.
//   Angle alone: θ̂ = wrap(θ_f − s_θ), H_robot = [0 0 −1], H_angle = 1; it is
//   compared with an observed θ modulo π (lineAngleDifference), because θ_f's
//   orientation says nothing about the side the sensor is on.
//   Case 1, one endpoint m₁ in the state: the line through m₁ with normal θ_f
//   is (a) with ρ = n(θ_f)·m₁, α = θ_f:
//     p' = n(θ_f)·(m₁ − s_t),   θ' = θ_f − s_θ,   then the p' < 0 flip;
//     ∂p'/∂m₁ = n(θ_f)ᵀ, ∂p'/∂θ_f = n⊥(θ_f)·(m₁ − s_t), ∂p'/∂s_t = −n(θ_f)ᵀ,
//     H_point = [σ n(θ_f)ᵀ; 0 0], H_angle = (σ n⊥(θ_f)·(m₁ − s_t), 1),
//     H_robot = [−σ n(θ_f)ᵀ  −σ n(θ_f)·R'(θ_r)L_t;  0 0 −1].
//   The thesis's eq. 4.35 writes n⊥(θ_f)·(m₁ − x_v) for p: with θ the normal
//   (eqs. 4.24, 4.29, 4.44) that is the coordinate along the line, not the
//   distance; and its eq. 4.37 drops the robot terms x_v cos θ + y_v sin θ
//   from ∂n₁/∂θ_f.
//   Case 2, both endpoints m₁, m₂ in the state: p from the line through the
//   endpoints, θ from θ_f (as the thesis's eq. 4.38). θ_f is the direction
//   fitted to the whole wall at every sighting and is what the θ row
//   corrects; the endpoints, corners a few centimetres uncertain, give the
//   offset. With u = m₂ − m₁, d = |u|, e = u/d, the endpoints' normal
//   k = (−e_y, e_x) (e turned +90°) and its orientation κ = sign(k·n(θ_f))
//   (piecewise constant; p is measured along θ_f's side of the normal, as θ):
//     w = m₁ − s_t, p' = κ k·w, θ' = θ_f − s_θ, then the p' < 0 flip.
//   With a = e·w (m₁'s place along the line from the foot of the sensor's
//   perpendicular): ∂(k·w)/∂u = −(a/d) kᵀ (turning the line about m₁), and
//   ∂(k·w)/∂w = kᵀ, so
//     H_m1 = [σκ (1 + a/d) kᵀ; 0 0],  H_m2 = [−σκ (a/d) kᵀ; 0 0],
//     H_angle = (0, 1),  H_robot = [−σκ kᵀ  −σκ k·R'(θ_r)L_t;  0 0 −1].
//   The thesis's eq. 4.38 omits the term (x₁y₂ − x₂y₁)/d (it is the distance
//   to the parallel through the map origin) and its eqs. 4.40–4.43 are not
//   the derivatives of eq. 4.38. Refused: endpoints closer than
//   kMinEndpointSeparation, or θ_f more than kMaxEndpointDisagreement from
//   the endpoints' normal (modulo π): no consistent state has that.
//   Augmentation (eq. 4.44 with the mount): θ_f = wrap(θ + s_θ), G_robot =
//   [0 0 1], G_z = [0 1] for z = (p, θ). Its covariance (eqs. 4.45, 4.47):
//     P_ff = G_r P_rr G_rᵀ + G_z R G_zᵀ = P_θrθr + R_θθ,
//     P_f,all = G_r P_r,all  (the heading's row, robot block included),
//   with R_θθ the θ variance of the total-least-squares fit, not the
//   two-endpoint T R Tᵀ that §4.3.3 found to underestimate.
//
// Functions return false with their outputs untouched on non-finite inputs
// (and, where they take covariances, on a non-finite, asymmetric or
// non-positive-semi-definite one). Jacobians are checked against central
// differences in line_models_test.cc; docs/maths.md, "Line landmarks".
#pragma once

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

using RowVector2 = Eigen::Matrix<double, 1, 2>;
using RowVector3 = Eigen::Matrix<double, 1, 3>;

// The line x cos θ + y sin θ = p in some frame (stated by each function).
struct PolarLine {
  double p = 0.0;      // m, distance from the frame's origin (>= 0 in outputs)
  double theta = 0.0;  // rad, direction of the normal towards the line ([-π, π) in outputs)

  Vector2 vector() const { return Vector2(p, theta); }
  bool allFinite() const { return std::isfinite(p) && std::isfinite(theta); }
};

// Endpoints closer than this (m) do not define a line direction.
constexpr double kMinEndpointSeparation = 1e-6;
// θ_f further than this (rad, modulo π) from the normal of the endpoints'
// line: the state is inconsistent and the orientation of p is undefined.
constexpr double kMaxEndpointDisagreement = 0.25 * kPi;

// a − b for line normal directions, modulo π, in [-π/2, π/2).
double lineAngleDifference(double a, double b);

// (a) Laser-frame observation z of the map-frame line `landmark`.
bool predictLineObservation(const Pose2& robot, const Pose2& laser, const PolarLine& landmark,
                            PolarLine* z, Matrix23* H_robot = nullptr,
                            Matrix2* H_landmark = nullptr);

// (a) Inverse: the map-frame line from a laser-frame observation z.
bool lineLandmarkFromObservation(const Pose2& robot, const Pose2& laser, const PolarLine& z,
                                 PolarLine* landmark, Matrix23* G_robot = nullptr,
                                 Matrix2* G_z = nullptr);

// Innovation ν = z − ẑ with ẑ written as (p̂, θ̂) or (−p̂, θ̂ + π), whichever has
// its normal within π/2 of z's, so ν = (difference of signed offsets along a
// common normal, lineAngleDifference(θ, θ̂)). J_innovation_prediction =
// ∂ν/∂ẑ = −diag(±1, 1): the filter uses −J_innovation_prediction·H as its H.
bool lineInnovation(const PolarLine& z, const PolarLine& z_hat, Vector2* innovation,
                    Matrix2* J_innovation_prediction = nullptr);

// (b) Laser-frame normal direction of the θ-only landmark θ_f (compare
// modulo π with lineAngleDifference).
bool predictLineAngle(const Pose2& robot, const Pose2& laser, double theta_f, double* theta,
                      RowVector3* H_robot = nullptr, double* H_angle = nullptr);

// (b) Case 1: the line through the point landmark m1 with normal θ_f.
bool predictLineFromAngleAndPoint(const Pose2& robot, const Pose2& laser, double theta_f,
                                  const Vector2& m1, PolarLine* z, Matrix23* H_robot = nullptr,
                                  Matrix2* H_point = nullptr, Vector2* H_angle = nullptr);

// (b) Case 2: p from the line through m1 and m2, θ from θ_f.
bool predictLineFromAngleAndEndpoints(const Pose2& robot, const Pose2& laser, double theta_f,
                                      const Vector2& m1, const Vector2& m2, PolarLine* z,
                                      Matrix23* H_robot = nullptr, Matrix2* H_m1 = nullptr,
                                      Matrix2* H_m2 = nullptr, Vector2* H_angle = nullptr);

// (b) Augmentation: θ_f from a laser-frame observation z = (p, θ).
bool lineAngleFromObservation(const Pose2& robot, const Pose2& laser, const PolarLine& z,
                              double* theta_f, RowVector3* G_robot = nullptr,
                              RowVector2* G_z = nullptr);

// First-order covariance of a new landmark, G_r P_rr G_rᵀ + G_z R G_zᵀ, for
// the (p, θ) landmark (2×2) and the θ-only landmark (variance). The rows
// against the rest of the state are G_r P_r,all. Refuses a non-finite,
// asymmetric or non-PSD robot_covariance (P_rr) or z_covariance (R).
bool newLineLandmarkCovariance(const Matrix3& robot_covariance, const Matrix2& z_covariance,
                               const Matrix23& G_robot, const Matrix2& G_z, Matrix2* covariance);
bool newLineAngleVariance(const Matrix3& robot_covariance, const Matrix2& z_covariance,
                          const RowVector3& G_robot, const RowVector2& G_z, double* variance);

}  // namespace ekf_slam
