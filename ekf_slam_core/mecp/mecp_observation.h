// Observation of an MECP feature (thesis §4.4.1, §4.4.3): the centre of its
// k member point landmarks, in range–bearing from the laser. The MECP is not
// a state element: its members are point landmarks of the state, and the
// caller keeps their indices for association (§4.4.4).
//
// Predicted, from the robot pose x_r, the laser mount `laser` (base_link →
// laser, as in point_observation_model.h) and the members m_1 … m_k (map
// frame):
//   c = (1/k) Σ m_i                                  (centre, map frame)
//   z = h(x_r, c) = (|l|, atan2(l_y, l_x)),  l = Rᵀ(s_θ)(c − s_t),  s = x_r ⊕ laser
//   H_r   = ∂h/∂x_r at c                            (2×3, as for a point)
//   H_m_i = (1/k) ∂h/∂c = (1/k) [l_x/ρ  l_y/ρ; −l_y/ρ²  l_x/ρ²] Rᵀ(s_θ)   (2×2, the same for every
//   i)
// with ρ = |l|. With the laser at the robot origin and x_c = c_x − x_v,
// y_c = c_y − y_v this is H_r = [−x_c/ρ  −y_c/ρ  0; y_c/ρ²  −x_c/ρ²  −1].
//
// Observed, from k readings (r_i, φ_i) in the laser frame with covariances
// R_i (readings independent, so R is block diagonal):
//   l_i = r_i (cos φ_i, sin φ_i),   ĉ = (1/k) Σ l_i,   ẑ = (|ĉ|, atan2(ĉ_y, ĉ_x))
//   T = ∂ẑ/∂(r_1, φ_1, …, r_k, φ_k) = P(ĉ) (1/k) [A_1 … A_k]             (2×2k)
//   P(ĉ) = [ĉ_x/ρ  ĉ_y/ρ; −ĉ_y/ρ²  ĉ_x/ρ²],  A_i = [cos φ_i  −r_i sin φ_i; sin φ_i  r_i cos φ_i]
//   cov(ẑ) ≈ T R Tᵀ = Σ T_i R_i T_iᵀ,  T_i the i-th 2×2 block of T.
// The averaging shrinks the Cartesian covariance about k-fold; the polar map
// P then divides the bearing's standard deviation by ρ.
//
// Conditioning: the robot lies inside the MECP, so the centre is often close
// to the laser, where the bearing's linearisation error grows like σ/ρ (σ:
// the centre's Cartesian standard deviation). Gate on ρ (several σ) before
// using the bearing in a filter update. The MECP's observation is a function
// of its members' readings: fusing it together with the same readings as
// point observations would count them twice.
//
// Both functions return false and leave every output untouched when an input
// is non-finite or malformed, or the centre is at the sensor origin.
#pragma once

#include <vector>

#include "ekf_slam_core/models/point_observation_model.h"

namespace ekf_slam {

using Matrix2X = Eigen::Matrix<double, 2, Eigen::Dynamic>;

// Predicted MECP observation of the landmarks `members` (map frame, k >= 1)
// from robot pose `robot`. H_members (if given) receives k blocks, one per
// member in order.
bool predictMecpObservation(const Pose2& robot, const Pose2& laser,
                            const std::vector<Vector2>& members, RangeBearing* z,
                            Matrix23* H_robot = nullptr, std::vector<Matrix2>* H_members = nullptr);

// The observed MECP from its members' readings `readings` (laser frame, k >=
// 1, range >= 0) and their (range, bearing) covariances
// `reading_covariances` ([m², m·rad; m·rad, rad²], symmetric, one per
// reading): the centre's range–bearing and its covariance T R Tᵀ (2×2).
// J_z_readings (if given) receives T, 2×2k, columns (r_1, φ_1, r_2, …).
bool observeMecp(const std::vector<RangeBearing>& readings,
                 const std::vector<Matrix2>& reading_covariances, RangeBearing* z,
                 Matrix2* covariance, Matrix2X* J_z_readings = nullptr);

}  // namespace ekf_slam
