// EKF-SLAM (thesis Ch. 2–4): the joint state of the robot pose and the
// landmarks in the map frame, its covariance, and the four stages predict /
// (observe) / update / augment. Landmarks are points (x, y), lines (p, θ) of
// their normal form, or line directions θ alone (the thesis's θ-only lines,
// §4.3.3, whose offset comes from endpoint point landmarks).
//
// The state is a value (FilterState, filter_state.h: the mean, the
// covariance, the landmarks' bookkeeping, and its layout). This class runs
// the filter on it: prediction, point updates and augmentation. Line landmarks
// (line_landmark_update.h) and the map's upkeep (map_maintenance.h) are
// units of their own acting on the same state; the members below that
// name them hand over to those units.
//
// Cost per operation with n = state size and k matched observations:
//   predict O(n) (only the robot rows/columns change), augment O(n),
//   update O(n²k) through a symmetric rank-2k downdate of P (no Joseph
//   product, no n×n×n multiply; P stays symmetric by construction).
// Every operation validates its input. On any status other than kOk the
// state is unchanged, so a caller can count, log and carry on.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cassert>
#include <cmath>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ekf_slam_core/filter/filter_state.h"
#include "ekf_slam_core/filter/filter_status.h"
#include "ekf_slam_core/models/line_observation_model.h"
#include "ekf_slam_core/models/odometry_motion_model.h"
#include "ekf_slam_core/models/point_observation_model.h"

namespace ekf_slam {

struct FilterOptions {
  MotionNoiseOptions motion_noise;
  Pose2 laser_pose;                      // base_link → laser (m, rad)
  double max_step_translation = 1.0;     // m: a larger odometry increment is a jump
  double max_step_rotation = kPi / 2.0;  // rad: |rot1| + |rot2| beyond this is a jump
  long tentative_max_age = 10;           // steps a once-seen landmark may wait; 0 = keep all
  // First-estimates Jacobians (Huang, Mourikis & Roumeliotis 2008): F uses the
  // predicted positions of consecutive steps and H each landmark's first
  // estimate, so that the linearised system keeps the unobservable global
  // heading unobservable. The standard EKF evaluates them at the newest
  // estimates and gains spurious heading information: its heading is
  // overconfident on long runs. Off: the textbook EKF (thesis).
  bool first_estimate_jacobians = false;

  // Whether an odometry increment is a jump (beyond max_step_*): the filter
  // refuses it, the pipeline counts a forced one and gives the full
  // smoother no wheel edge across it. A non-finite increment is one too.
  bool isJump(const OdometryControl& u) const {
    return !(std::abs(u.trans) <= max_step_translation &&
             std::abs(wrapAngle(u.rot1 + u.rot2)) <= max_step_rotation);
  }

  // The fields a configuration sets; laser_pose is a pose, checked in
  // validate() (finite).
  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("max_step_translation", max_step_translation, Bounds::above(0.0, "m"));
    v.flag("first_estimate_jacobians", first_estimate_jacobians);
    v.number("max_step_rotation", max_step_rotation, Bounds::openClosed(0.0, 2.0 * kPi, "rad"));
    v.integer("tentative_max_age", tentative_max_age, Bounds::closed(0, 1e6, "steps"));
    v.section("motion_noise", motion_noise);
  }

  std::string validate() const;  // empty when valid, else names the bad field
};

// A point feature measured in the laser frame.
struct PointObservation {
  RangeBearing z;
  Matrix2 covariance = Matrix2::Identity();  // of (range m, bearing rad): m², m·rad, rad²
};

// A line measured in the laser frame: its normal form (p, θ) and the
// covariance of the fit.
struct LineObservation {
  PolarLine z;
  Matrix2 covariance = Matrix2::Identity();  // of (p m, θ rad): m², m·rad, rad²
};

// A line observation matched to a line landmark. For a θ-only landmark
// the offset comes from up to two point landmarks on the line (its
// endpoints, thesis eqs. 4.35, 4.38): with none only θ is measured.
struct LineMatch {
  int observation = -1;            // index into the line observation vector
  int landmark_id = -1;            // a kLine or kLineAngle landmark
  int endpoint_ids[2] = {-1, -1};  // kLineAngle: point landmarks on the line (-1: none)
};

struct PointMatch {
  int observation = -1;  // index into the observation vector
  int landmark_id = -1;
};

class EkfSlam {
 public:
  static constexpr int kPoseDim = FilterState::kPoseDim;
  static constexpr int kPointDim = 2;
  // A slot must name a landmark in the state (slotOf() >= 0).
  int landmarkIndex(int slot) const { return state_.landmarkIndex(slot); }
  LandmarkKind landmarkKind(int slot) const {
    assert(slot >= 0 && slot < landmarkCount());
    return state_.landmarks[slot].kind;
  }

  // Options must be valid (check options.validate() first); the initial
  // covariance must be symmetric PSD.
  explicit EkfSlam(const FilterOptions& options, const Pose2& initial_pose = Pose2(),
                   const Matrix3& initial_covariance = Matrix3::Zero());

  // Prediction from two successive odometry poses (§3.4.2) over dt seconds.
  // Starts a new step (the step counter drives landmark bookkeeping). An
  // increment beyond max_step_* is refused as a jump (kOdometryJump) unless
  // `jump_check` is false: a move the caller knows was made (the robot
  // driven while SLAM was paused), whose noise the model scales with it.
  FilterStatus predict(const Pose2& odom_previous, const Pose2& odom_current, double dt,
                       bool jump_check = true);
  FilterStatus predict(const OdometryControl& u, double dt, bool jump_check = true);

  struct Prediction {
    RangeBearing z;      // predicted observation
    Matrix23 H_robot;    // ∂z/∂x_r
    Matrix2 H_landmark;  // ∂z/∂m
    Matrix2 HPHt;        // H P Hᵀ: innovation covariance without the sensor noise
  };
  // Predicted observation of the point landmark in `slot`; false when
  // undefined (landmark at the sensor origin) or when it is not a point.
  bool predictObservation(int slot, Prediction* out) const;

  // Batch update with all matched observations of a scan. On success `nis`
  // (if given) receives νᵢᵀ Sᵢ⁻¹ νᵢ of each match, in the order of `matches`.
  FilterStatus update(const std::vector<PointObservation>& observations,
                      const std::vector<PointMatch>& matches, std::vector<double>* nis = nullptr);

  // Adds a new landmark with full cross-covariances (§4.2.4).
  FilterStatus augment(const PointObservation& observation, int* new_id = nullptr);

  // Batch update with matched line observations (after the points' update
  // of the same scan: sequential batches are the joint update when the
  // noises are independent). kLine: the (p, θ) innovation, the p-sign and
  // θ-wrap ambiguity resolved towards the prediction; kLineAngle: θ alone
  // (compared modulo π), or (p, θ) with one or two endpoint points. Every
  // match is checked before the state is touched; `nis` as for update().
  FilterStatus updateLines(const std::vector<LineObservation>& observations,
                           const std::vector<LineMatch>& matches,
                           std::vector<double>* nis = nullptr);
  // For association: the innovation updateLines would use for `match`
  // (the same linearisation, p-sign and θ-wrap resolved towards the
  // prediction) and its covariance S = H P Hᵀ + R, 1 × 1 for a θ-only
  // landmark without endpoints, else 2 × 2. On any status other than kOk
  // (the one updateLines would refuse the match with) the outputs are
  // untouched.
  FilterStatus predictLineMatch(const LineObservation& observation, const LineMatch& match,
                                Eigen::VectorXd* innovation,
                                Eigen::MatrixXd* innovation_covariance) const;
  // Adds a line landmark: kLine (p, θ) with its 2 × 2 block, or kLineAngle
  // θ_f = θ + s_θ alone (thesis eqs. 4.44–4.47), cross-covariances from the
  // robot's rows.
  FilterStatus augmentLine(const LineObservation& observation, LandmarkKind kind,
                           int* new_id = nullptr);
  // The line landmark in `slot` (kLine) or its direction (kLineAngle).
  PolarLine lineLandmark(int slot) const;
  double lineAngle(int slot) const { return state_.x(landmarkIndex(slot)); }

  // Removes landmarks seen only once whose age exceeds
  // options().tentative_max_age steps. Returns how many were removed.
  int pruneTentative();
  bool removeLandmark(int id);
  // Removes every listed landmark in one pass over P (ids that do not exist
  // are skipped). Returns how many were removed.
  int removeLandmarks(const std::vector<int>& ids);

  // Two point landmarks that are one: the joint covariance says their difference is
  // zero within the gate (squared Mahalanobis distance of x_a − x_b under
  // P_aa + P_bb − P_ab − P_ba + b²I below `gate`, where b (m) is how far two
  // extractions of the same corner may disagree beyond their noise model:
  // a corner and a segment end, or two views of a rasterised corner). Fuses
  // them by conditioning the whole state on x_a − x_b ~ N(0, b²I) (b = 0: an
  // exact constraint), then removes `drop_id`; `keep_id` gains its sightings.
  // kUnknownLandmark for a missing id, kBadObservation when the two are
  // farther apart than the gate allows (nothing changes then),
  // kSingularInnovation when the difference covariance is not positive.
  FilterStatus mergeLandmarks(int keep_id, int drop_id, double gate, double bias_sigma = 0.0);

  // Checks each landmark of `ids` against every landmark within
  // `max_distance` (m) and merges pairs that are one (mergeLandmarks with
  // `gate`), keeping the older landmark. Returns the (kept, dropped) pairs.
  std::vector<std::pair<int, int>> mergeDuplicates(const std::vector<int>& ids, double gate,
                                                   double max_distance, double bias_sigma = 0.0);

  // Seeds a landmark from a prior map (e.g. one saved earlier): mean and
  // covariance in the map frame, uncorrelated with the pose and the other
  // landmarks. Keeps `id` (later landmarks get larger ids). Refused with
  // kDuplicateLandmark when the id exists, kSingularInnovation when the
  // covariance is not symmetric positive definite, kUnrepresentablePrior
  // when its larger eigenvalue exceeds kMaxPriorVariance or its smaller one
  // is below kMinPriorEigenvalueRatio times the larger (updates would then
  // lose positive definiteness to rounding).
  static constexpr double kMaxPriorVariance = 1e6;  // m² (σ = 1 km)
  static constexpr double kMinPriorEigenvalueRatio = 1e-12;
  FilterStatus addLandmark(int id, const Vector2& position, const Matrix2& covariance,
                           int observations = 2);
  // The same for a (p, θ) line landmark, covariance of (p, θ) (m², m·rad,
  // rad²). A line given with p < 0 is stored in normal form, (−p, θ + π)
  // with the p row and column of its covariance negated (the same line);
  // θ is wrapped. Refused as addLandmark, and with kUnrepresentablePrior
  // also when the variance of θ exceeds kMaxPriorAngleVariance.
  static constexpr double kMaxPriorAngleVariance = kPi * kPi;  // rad² (σ = π)
  FilterStatus addLineLandmark(int id, const PolarLine& line, const Matrix2& covariance,
                               int observations = 2);
  // A θ-only line landmark: the normal's direction θ (wrapped) and its
  // variance (rad², positive, at most kMaxPriorAngleVariance; else
  // kSingularInnovation or kUnrepresentablePrior).
  FilterStatus addLineAngleLandmark(int id, double theta, double variance, int observations = 2);

  // Localisation only when false: augment() refuses (kMappingDisabled), so
  // the map keeps its landmarks and gains none. On by default.
  void setMappingEnabled(bool enabled) { state_.mapping_enabled = enabled; }
  bool mappingEnabled() const { return state_.mapping_enabled; }

  Pose2 pose() const { return state_.pose(); }
  Matrix3 poseCovariance() const { return state_.poseCovariance(); }
  int landmarkCount() const { return state_.landmarkCount(); }
  int stateDim() const { return state_.dim; }
  int slotOf(int id) const { return state_.slotOf(id); }  // -1 when no landmark has this id
  // Of a point landmark, or a (p, θ) line's (p, θ) and its 2 × 2 block.
  Vector2 landmarkPosition(int slot) const { return state_.landmarkPosition(slot); }
  Matrix2 landmarkCovariance(int slot) const {
    return state_.P.block<2, 2>(landmarkIndex(slot), landmarkIndex(slot));
  }
  // Of a θ-only line landmark's direction (rad²).
  double lineAngleVariance(int slot) const {
    return state_.P(landmarkIndex(slot), landmarkIndex(slot));
  }
  const std::vector<LandmarkInfo>& landmarks() const { return state_.landmarks; }
  // Cross-covariance of two landmarks' positions (P_ab, 2 × 2).
  Matrix2 landmarkCrossCovariance(int slot_a, int slot_b) const {
    return state_.landmarkCrossCovariance(slot_a, slot_b);
  }
  // Of the pose and a landmark's position (P_rm, 3 × 2).
  Eigen::Matrix<double, 3, 2> poseLandmarkCovariance(int slot) const {
    return state_.P.block<3, 2>(0, landmarkIndex(slot));
  }
  Eigen::Ref<const Eigen::VectorXd> state() const { return state_.x.head(state_.dim); }
  // The whole n × n covariance, a copy (O(n²)): for tests and tools; the
  // accessors above read single blocks.
  Eigen::MatrixXd covariance() const { return state_.covariance(); }
  long step() const { return state_.step; }
  // F of the last accepted prediction (for the smoother's record).
  const Matrix3& lastMotionJacobian() const { return state_.last_F; }
  const FilterOptions& options() const { return options_; }

  // Everything the filter knows, as a value (a snapshot), and back: a
  // restored state continues exactly where the snapshot was taken.
  const FilterState& filterState() const { return state_; }
  void restore(const FilterState& state) { state_ = state; }

  // Normalised estimation error squared of the pose against ground truth.
  double poseNees(const Pose2& truth) const;

  // Moves pieces of the map rigidly, as a loop-closing back end moves the
  // key scans they hang off: the robot by `robot_correction`, each listed
  // landmark by its correction (landmarks not listed stay). A correction C
  // acts in the map frame, x ↦ C ∘ x (a position m ↦ R_C m + t_C, a line
  // (p, θ) ↦ (p + n(θ + φ_C)·t_C, θ + φ_C), a direction θ ↦ θ + φ_C). The
  // covariance follows to first order: P ↦ J P Jᵀ with J block-diagonal,
  // diag(R_C, 1) for the robot, R_C for a point, [1 n⊥(θ')·t_C; 0 1] for a
  // line (its p row negated when p changes sign) and 1 for a direction.
  // First estimates (first_estimate_jacobians) move too.
  // Landmark ids that do not exist are skipped.
  void reanchor(const Pose2& robot_correction,
                const std::vector<std::pair<int, Pose2>>& landmark_corrections);

 private:
  FilterOptions options_;
  FilterState state_;
};

}  // namespace ekf_slam
