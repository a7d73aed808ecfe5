// EKF-SLAM (thesis Ch. 2–4): the joint state of the robot pose and the
// landmarks in the map frame, its covariance, and the four stages predict /
// (observe) / update / augment. Landmarks are points (x, y), lines (p, θ) of
// their normal form, or line directions θ alone (the thesis's θ-only lines,
// §4.3.3, whose offset comes from endpoint point landmarks).
//
// State layout (use the helpers, never bare indices):
//   x = [x_r (kPoseDim = 3: x, y, θ) | landmark 0 | landmark 1 | …]
//   each landmark landmarkDim(kind) long, from landmarkIndex(slot) on.
// Landmarks keep a stable id; their slot and index change when others are
// removed.
//
// Cost per operation with n = state size and k matched observations:
//   predict O(n) (only the robot rows/columns change), augment O(n),
//   update O(n²k) through a symmetric rank-2k downdate of P (no Joseph
//   product, no n×n×n multiply; P stays symmetric by construction).
// The stored P is current in its lower triangle; of the upper one only the
// pose rows and each landmark's 2 × 2 block are kept, O(n) after a downdate
// (mirroring the whole triangle would cost about as much as the downdate).
// An update or merge first fills the landmark columns it reads from the
// lower triangle; covariance() returns a full symmetric copy.
//
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

enum class LandmarkKind {
  kPoint,      // (x, y)
  kLine,       // (p, θ): x cos θ + y sin θ = p in the map frame, p >= 0
  kLineAngle,  // θ alone: the direction of a line's normal in the map frame
};
constexpr int landmarkDim(LandmarkKind kind) { return kind == LandmarkKind::kLineAngle ? 1 : 2; }
const char* toString(LandmarkKind kind);

// A line observation matched to a line landmark. For a θ-only landmark
// the offset comes from up to two point landmarks on the line (its
// endpoints, thesis eqs. 4.35, 4.38): with none only θ is measured.
struct LineMatch {
  int observation = -1;            // index into the line observation vector
  int landmark_id = -1;            // a kLine or kLineAngle landmark
  int endpoint_ids[2] = {-1, -1};  // kLineAngle: point landmarks on the line (-1: none)
};

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

struct PointMatch {
  int observation = -1;  // index into the observation vector
  int landmark_id = -1;
};

// An observation z = h(x_r, m_a, m_b, …) of dimension d, linearised by
// the caller at the current estimate: the filter applies the EKF update
// with H = [J_z_pose, 0 …, J_z_landmarks[0] at m_a's columns, …] and
// innovation ν = z − h(x̂) (angles already wrapped by the caller).
struct GenericObservation {
  Eigen::VectorXd innovation;                  // d
  Eigen::MatrixXd J_z_pose;                    // d × kPoseDim
  std::vector<int> landmark_ids;               // each at most once
  std::vector<Eigen::MatrixXd> J_z_landmarks;  // d × landmarkDim(kind), one per id
  Eigen::MatrixXd noise;                       // d × d, symmetric, the observation's R
};

class EkfSlam {
 public:
  static constexpr int kPoseDim = 3;
  static constexpr int kPointDim = 2;
  // A slot must name a landmark in the state (slotOf() >= 0).
  int landmarkIndex(int slot) const {
    assert(slot >= 0 && slot < landmarkCount());
    return landmarks_[slot].index;
  }
  LandmarkKind landmarkKind(int slot) const {
    assert(slot >= 0 && slot < landmarkCount());
    return landmarks_[slot].kind;
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
  // Update with one linearised observation of the pose and some landmarks
  // that no other entry point models, e.g. the centre of an MECP's members
  // (thesis §4.4.3). Defined in generic_update.cc; see GenericObservation.
  // Checked before the state is touched: kUnknownLandmark for a missing
  // id, kBadObservation for a repeated id or mismatched sizes,
  // kNonFiniteInput, kSingularInnovation when S is not positive definite.
  // `nis` (if given) receives νᵀ S⁻¹ ν.
  FilterStatus updateGeneric(const GenericObservation& observation, double* nis = nullptr);
  // The line landmark in `slot` (kLine) or its direction (kLineAngle).
  PolarLine lineLandmark(int slot) const;
  double lineAngle(int slot) const { return x_(landmarkIndex(slot)); }

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
  void setMappingEnabled(bool enabled) { mapping_enabled_ = enabled; }
  bool mappingEnabled() const { return mapping_enabled_; }

  Pose2 pose() const { return Pose2(x_(0), x_(1), x_(2)); }
  Matrix3 poseCovariance() const { return P_.topLeftCorner<3, 3>(); }
  int landmarkCount() const { return static_cast<int>(landmarks_.size()); }
  int stateDim() const { return dim_; }
  int slotOf(int id) const;  // -1 when no landmark has this id
  // Of a point landmark, or a (p, θ) line's (p, θ) and its 2 × 2 block.
  Vector2 landmarkPosition(int slot) const { return x_.segment<2>(landmarkIndex(slot)); }
  Matrix2 landmarkCovariance(int slot) const {
    return P_.block<2, 2>(landmarkIndex(slot), landmarkIndex(slot));
  }
  // Of a θ-only line landmark's direction (rad²).
  double lineAngleVariance(int slot) const { return P_(landmarkIndex(slot), landmarkIndex(slot)); }
  const std::vector<LandmarkInfo>& landmarks() const { return landmarks_; }
  // Cross-covariance of two landmarks' positions (P_ab, 2 × 2).
  Matrix2 landmarkCrossCovariance(int slot_a, int slot_b) const;
  // Of the pose and a landmark's position (P_rm, 3 × 2).
  Eigen::Matrix<double, 3, 2> poseLandmarkCovariance(int slot) const {
    return P_.block<3, 2>(0, landmarkIndex(slot));
  }
  Eigen::Ref<const Eigen::VectorXd> state() const { return x_.head(dim_); }
  // The whole n × n covariance, a copy (O(n²)): for tests and tools; the
  // accessors above read single blocks.
  Eigen::MatrixXd covariance() const;
  long step() const { return step_; }
  // F of the last accepted prediction (for the smoother's record).
  const Matrix3& lastMotionJacobian() const { return last_F_; }
  const FilterOptions& options() const { return options_; }

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
  void reserve(int dim);
  struct LinearisedLine;
  FilterStatus linearizeLineMatch(const LineObservation& observation, const LineMatch& match,
                                  LinearisedLine* out) const;
  // The update's last step, shared by points and lines: x += W L⁻¹ ν and
  // the downdate P −= W Wᵀ of the lower triangle, W = P Hᵀ L⁻ᵀ.
  void applyGain(const Eigen::MatrixXd& PHt, const Eigen::LLT<Eigen::MatrixXd>& llt,
                 const Eigen::VectorXd& innovation);
  void mirrorPoseRowsAndLandmarkBlocks();
  void fillLandmarkColumns(const std::vector<int>& slots);
  void removeSlots(const std::vector<int>& slots);
  // Appends a landmark of `kind` at the end of the state (its mean and the
  // rows already written by the caller) and returns its id.
  int appendLandmark(LandmarkKind kind, int id, int observations, const Vector2& first_estimate);

  FilterOptions options_;
  // Storage with spare capacity so that augmentation does not reallocate the
  // n×n matrix every time; only the leading dim_ rows/columns are live.
  Eigen::VectorXd x_;
  Eigen::MatrixXd P_;
  int dim_ = kPoseDim;
  std::vector<LandmarkInfo> landmarks_;  // by slot
  std::unordered_map<int, int> slot_of_id_;
  int next_id_ = 0;
  long step_ = 0;
  Matrix3 last_F_ = Matrix3::Identity();
  bool have_prior_position_ = false;  // first-estimates Jacobians: the last predicted position
  Vector2 prior_position_ = Vector2::Zero();
  bool mapping_enabled_ = true;
};

}  // namespace ekf_slam
