// The EKF-SLAM state as a value: the joint mean of the robot pose and the
// landmarks in the map frame, its covariance, and the landmarks'
// bookkeeping. Everything the filter knows is here, so that a copy of it is
// a snapshot (to save, to restore, to compare). EkfSlam (ekf_slam.h) runs
// the filter on it; lines (line_landmark_update.h) and the map's upkeep
// (map_maintenance.h) are units of their own that act on it through the
// storage operations below, which keep its invariants.
//
// State layout (use the helpers, never bare indices):
//   x = [x_r (kPoseDim = 3: x, y, θ) | landmark 0 | landmark 1 | …]
//   each landmark landmarkDim(kind) long, from landmarkIndex(slot) on.
// Landmarks keep a stable id; their slot and index change when others are
// removed. x and P have spare capacity so that augmentation does not
// reallocate the n×n matrix every time; only the leading dim rows and
// columns are live.
//
// The stored P is current in its lower triangle; of the upper one only the
// pose rows and each landmark's 2 × 2 block are kept, O(n) after a downdate
// (mirroring the whole triangle would cost about as much as the downdate).
// An update or merge first fills the landmark columns it reads from the
// lower triangle (fillLandmarkColumns); covariance() returns a full
// symmetric copy.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cassert>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/filter/filter_status.h"
#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

enum class LandmarkKind {
  kPoint,      // (x, y)
  kLine,       // (p, θ): x cos θ + y sin θ = p in the map frame, p >= 0
  kLineAngle,  // θ alone: the direction of a line's normal in the map frame
};
constexpr int landmarkDim(LandmarkKind kind) { return kind == LandmarkKind::kLineAngle ? 1 : 2; }
const char* toString(LandmarkKind kind);

struct LandmarkInfo {
  int id = -1;
  LandmarkKind kind = LandmarkKind::kPoint;
  int index = 0;            // of its first component in the state (changes when others go)
  int observations = 0;     // the creating observation plus every accepted match
  long created_step = 0;    // filter step at augmentation
  long last_seen_step = 0;  // filter step of the last match
  // When created, for first-estimates Jacobians: a point's position, a
  // line's (p, θ) (kept in the state's coordinates when p changes sign),
  // a direction's (0, θ_f).
  Vector2 first_estimate = Vector2::Zero();
};

struct FilterState {
  static constexpr int kPoseDim = 3;

  // The initial covariance must be symmetric PSD.
  explicit FilterState(const Pose2& initial_pose = Pose2(),
                       const Matrix3& initial_covariance = Matrix3::Zero());

  Eigen::VectorXd x;  // the mean, live in its first `dim` entries
  Eigen::MatrixXd P;  // the covariance, live in its leading dim × dim block
  int dim = kPoseDim;
  std::vector<LandmarkInfo> landmarks;  // by slot
  std::unordered_map<int, int> slot_of_id;
  int next_id = 0;                       // of the next augmented landmark
  long step = 0;                         // predictions so far
  Matrix3 last_F = Matrix3::Identity();  // of the last accepted prediction
  // First-estimates Jacobians: the last predicted position.
  bool have_prior_position = false;
  Vector2 prior_position = Vector2::Zero();
  bool mapping_enabled = true;  // false: augmentation refused (localisation)

  Pose2 pose() const { return Pose2(x(0), x(1), x(2)); }
  Matrix3 poseCovariance() const { return P.topLeftCorner<3, 3>(); }
  int landmarkCount() const { return static_cast<int>(landmarks.size()); }
  int slotOf(int id) const;  // -1 when no landmark has this id
  // A slot must name a landmark in the state (slotOf() >= 0).
  int landmarkIndex(int slot) const {
    assert(slot >= 0 && slot < landmarkCount());
    return landmarks[slot].index;
  }
  Vector2 landmarkPosition(int slot) const { return x.segment<2>(landmarkIndex(slot)); }
  Matrix2 landmarkCrossCovariance(int slot_a, int slot_b) const;  // P_ab, 2 × 2
  Eigen::MatrixXd covariance() const;  // the whole n × n, a copy (O(n²))

  // Storage operations, each keeping the layout and the stored triangles.
  // Room for `needed` entries (the live ones kept).
  void reserve(int needed);
  // The update's last step, shared by every kind of observation: with
  // S = L Lᵀ and W = P Hᵀ L⁻ᵀ, x += W L⁻¹ ν and the downdate P −= W Wᵀ of
  // the lower triangle; the heading is wrapped.
  void applyGain(const Eigen::MatrixXd& PHt, const Eigen::LLT<Eigen::MatrixXd>& llt,
                 const Eigen::VectorXd& innovation);
  // After a downdate, O(n): the upper triangle of the pose rows and of each
  // landmark's 2 × 2 block, which the predictions read.
  void mirrorPoseRowsAndLandmarkBlocks();
  // The listed landmarks' columns above their diagonal block, from the
  // lower triangle, before an update reads them.
  void fillLandmarkColumns(const std::vector<int>& slots);
  // Removes the landmarks in `slots` (each at most once), moving the kept
  // entries down in place.
  void removeSlots(const std::vector<int>& slots);
  // Appends a landmark of `kind` at the end of the state (its mean and the
  // rows already written by the caller) and returns its id.
  int appendLandmark(LandmarkKind kind, int id, int observations, const Vector2& first_estimate);
};

// Checks the updates share. A 2 × 2 covariance must be finite, symmetric
// and positive definite.
bool isValidCovariance2(const Matrix2& c);
// Symmetrises the stacked innovation covariance S and factors it; kOk when
// S = L Lᵀ with a positive diagonal.
FilterStatus factorInnovation(Eigen::MatrixXd* S, Eigen::LLT<Eigen::MatrixXd>* llt);

}  // namespace ekf_slam
