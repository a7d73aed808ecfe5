// Laser scan matching: the pose of a scan against a reference point set, by
// point-to-line ICP (Censi 2008's metric, Gauss-Newton on the SE(2) pose)
// with a robust (Huber) kernel. The odometry gives the initial guess; the
// matcher refines it. Wheel odometry on the Freiburg logs drifts by degrees
// per metre, while consecutive LMS200 scans of walls pin the relative pose
// down to millimetres, so this increment is a much better control for the
// filter than the odometry increment (docs/offline.md, measured).
//
// Maths, in the code's symbols: a scan point p (base_link frame) is placed
// in the reference frame by the pose T = (x, y, θ): q(T) = R(θ) p + t. Its
// correspondence is the nearest reference point m within a gate, with unit
// normal n (from the principal axes of m's neighbours). The residual is the
// distance to the tangent line through m,
//   r = nᵀ (R(θ) p + t − m),
//   ∂r/∂(x, y, θ) = [n_x, n_y, nᵀ R'(θ) p],  R'(θ) p = (−p_y', p_x') rotated.
// The odometry guess g enters as a prior with information Λ =
// diag(σ_t⁻², σ_t⁻², σ_θ⁻²), so that a direction the scan does not constrain
// (along a featureless corridor) stays at the guess instead of following the
// noise. Each Gauss-Newton step solves
//   (Σ w Jᵀ J / σ_p² + Λ) δ = −(Σ w J r / σ_p² + Λ (x − g))
// with Huber weights w = min(1, huber_delta / |r|). The correspondence gate shrinks from
// initial_correspondence_distance to correspondence_distance over the first
// iterations, so a guess off by a few decimetres still converges while the
// final estimate uses only close pairs.
#pragma once

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/models/odometry_motion_model.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

struct ScanMatcherOptions {
  bool enabled = true;                           // false: the raw odometry is the control (thesis)
  double initial_correspondence_distance = 0.5;  // m: pairing gate at the first iteration
  double correspondence_distance = 0.15;         // m: pairing gate once the estimate has settled
  double huber_delta = 0.03;                     // m: residuals beyond count linearly (robust)
  double point_sigma = 0.02;  // m: 1-sigma point-to-line residual (range noise + wall roughness)
  double prior_sigma_translation = 0.1;     // m: 1-sigma of the odometry guess, per axis
  double prior_sigma_rotation = 0.05;       // rad: 1-sigma of the odometry guess's heading
  int max_iterations = 30;                  // Gauss-Newton steps per match
  double convergence_step = 1e-5;           // m or rad: a smaller step ends the iterations
  double min_point_spacing = 0.05;          // m: scan points closer than this are thinned
  double max_range = 30.0;                  // m: farther readings are not matched
  double normal_radius = 0.25;              // m: neighbours used to fit a reference normal
  int min_correspondences = 40;             // fewer paired points: the match is refused
  double min_inlier_fraction = 0.4;         // of the scan's points within the final gate
  double max_correction_translation = 0.5;  // m: a larger change of the odometry guess is refused
  double max_correction_rotation = 0.35;    // rad: likewise for the heading (20 deg)
  // Reference the scans are matched against: "local" = the last
  // local_map_scans key scans (pure scan-matching odometry, drifts slowly);
  // "global" = every key scan ever accepted, merged into one point map
  // (points closer than map_point_spacing to a map point are not added), so
  // a revisited place is matched against what was seen there before and the
  // drift is pulled back (scan-to-map matching, as Hector SLAM does).
  std::string map_mode = "global";
  double map_point_spacing = 0.05;  // m: global map resolution
  int local_map_scans = 8;          // key scans kept as the reference (local mode)
  double keyscan_distance = 0.15;   // m of travel before the scan joins the reference …
  double keyscan_angle = 0.1;       // rad … or this much turn
  // Check against the wheels. The match's increment since the last scan is
  // compared with the odometry increment: their difference d, against the
  // odometry increment's covariance Σ (the wheel noise model, G Q Gᵀ) plus
  // the floors below (time stamping and the matcher's own jitter), must pass
  // dᵀ Σ⁻¹ d ≤ χ²₃(odometry_gate_probability). A match that fails is refused
  // (counted) and the odometry increment is used, so a match that would move
  // the robot where its wheels say it cannot have gone never enters.
  // The floors make it a test for gross errors only: beyond the wheel model,
  // a scan's match may differ from the odometry by about 4 floors (20 cm,
  // 12 deg) before it is refused.
  // The odometry may also be stamped late or early against the scan (an
  // unsynchronised clock, a sample that arrived late): the motion during
  // odometry_check_sigma_time at the step's speed is added along the step.
  // A scan stamped no later than the previous one is not checked (counted):
  // the odometry looked up at such a stamp is where the robot was before,
  // not where the scan was taken, so its increment says nothing of the
  // match (logs whose clock steps back, as Intel's does).
  double odometry_gate_probability = 0.999;        // 0: no check
  double odometry_check_sigma_translation = 0.05;  // m, floor per scan (1 sigma)
  double odometry_check_sigma_rotation = 0.0524;   // rad, floor per scan (1 sigma, 3 deg)
  double odometry_check_sigma_time = 0.2;          // s, 1 sigma of the stamps' disagreement

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.flag("enabled", enabled);
    v.number("initial_correspondence_distance", initial_correspondence_distance,
             Bounds::openClosed(0.0, 100.0, "m"));
    v.number("correspondence_distance", correspondence_distance,
             Bounds::openClosed(0.0, 100.0, "m"));
    v.number("huber_delta", huber_delta, Bounds::openClosed(0.0, 100.0, "m"));
    v.number("point_sigma", point_sigma, Bounds::openClosed(0.0, 100.0, "m"));
    v.number("prior_sigma_translation", prior_sigma_translation, Bounds::above(0.0, "m"));
    v.number("prior_sigma_rotation", prior_sigma_rotation, Bounds::above(0.0, "rad"));
    v.integer("max_iterations", max_iterations, Bounds::closed(1, 10000));
    v.number("convergence_step", convergence_step, Bounds::openClosed(0.0, 1.0, "m or rad"));
    v.number("min_point_spacing", min_point_spacing, Bounds::closed(0.0, 10.0, "m"));
    v.number("max_range", max_range, Bounds::above(0.0, "m"));
    v.number("normal_radius", normal_radius, Bounds::openClosed(0.0, 10.0, "m"));
    v.integer("min_correspondences", min_correspondences, Bounds::closed(3, 100000));
    v.number("min_inlier_fraction", min_inlier_fraction, Bounds::closed(0.0, 1.0));
    v.number("max_correction_translation", max_correction_translation, Bounds::above(0.0, "m"));
    v.number("max_correction_rotation", max_correction_rotation,
             Bounds::openClosed(0.0, 2.0 * kPi, "rad"));
    v.text("map_mode", map_mode, {"local", "global"});
    v.number("map_point_spacing", map_point_spacing, Bounds::closed(0.0, 10.0, "m"));
    v.integer("local_map_scans", local_map_scans, Bounds::closed(1, 10000, "scans"));
    v.number("keyscan_distance", keyscan_distance, Bounds::atLeast(0.0, "m"));
    v.number("keyscan_angle", keyscan_angle, Bounds::closed(0.0, 2.0 * kPi, "rad"));
    v.number("odometry_gate_probability", odometry_gate_probability, Bounds::closedOpen(0.0, 1.0));
    v.number("odometry_check_sigma_translation", odometry_check_sigma_translation,
             Bounds::above(0.0, "m"));
    v.number("odometry_check_sigma_rotation", odometry_check_sigma_rotation,
             Bounds::openClosed(0.0, 2.0 * kPi, "rad"));
    v.number("odometry_check_sigma_time", odometry_check_sigma_time,
             Bounds::closed(0.0, 100.0, "s"));
  }

  // Beyond each field's bounds: initial_correspondence_distance >=
  // correspondence_distance.
  std::string validate() const;  // empty when valid, else names the bad field
};

// The cells of a hash grid by key, numbered in the order they were added:
// open addressing with linear probing in a power-of-two table kept at most
// half full. Nearest-point queries look up nine cells each, and a flat
// table does so without a node per cell or a division by a prime.
class CellIndex {
 public:
  using Key = long long;
  // The number of key's cell, or -1 when it has none.
  int find(Key key) const;
  // The number of key's cell; a new key gets the next number.
  int findOrAdd(Key key);
  void clear();
  int size() const { return count_; }

 private:
  size_t slotOf(Key key) const;
  void grow();

  std::vector<Key> keys_;
  std::vector<int> cells_;  // per slot: the cell's number, -1 where empty
  int count_ = 0;
  int shift_ = 64;  // 64 − log2(table size)
};

// A reference point set with normals and a hash grid for nearest neighbours.
class PointCloudReference {
 public:
  // Points in one frame; normals are fitted from neighbours within `normal_radius`;
  // points with too few neighbours or no dominant direction are dropped.
  PointCloudReference(const std::vector<Vector2>& points, double normal_radius, double cell_size);

  // Adds points with their normals; a point within `min_spacing` of an
  // existing point is not added (the map does not grow on revisits).
  void insert(const std::vector<Vector2>& points, const std::vector<Vector2>& normals,
              double min_spacing);

  // Index of the nearest point within `max_distance` of p, or -1.
  int nearest(const Vector2& p, double max_distance) const;
  // Whether any point lies within `distance` of p: nearest(p, distance) >= 0,
  // answered at the first such point.
  bool anyWithin(const Vector2& p, double distance) const;
  const std::vector<Vector2>& points() const { return points_; }
  const std::vector<Vector2>& normals() const { return normals_; }
  size_t size() const { return points_.size(); }

 private:
  using CellKey = long long;
  CellKey key(int ix, int iy) const;
  void cellOf(const Vector2& p, int* ix, int* iy) const;
  void buildGrid();
  void addToGrid(int index);

  std::vector<Vector2> points_;
  std::vector<Vector2> normals_;
  double cell_size_;
  // The points of each cell, in index order, by the numbers of cell_index_.
  const std::vector<int>* cell(int ix, int iy) const;
  CellIndex cell_index_;
  std::vector<std::vector<int>> cells_;
};

struct MatchResult {
  bool ok = false;
  Pose2 pose;               // refined pose of the scan points' frame in the reference frame
  int correspondences = 0;  // pairs within the final gate
  double inlier_fraction = 0.0;
  double rms_residual = 0.0;  // m, over the final pairs
  int iterations = 0;
  std::string message;  // why the match was refused
};

// Aligns `points` (in their own frame) to `reference`, starting from `guess`.
MatchResult matchPoints(const std::vector<Vector2>& points, const PointCloudReference& reference,
                        const Pose2& guess, const ScanMatcherOptions& options);

// Valid readings of a scan as points in the robot frame (through the laser
// mount), thinned to min_point_spacing and limited to max_range.
std::vector<Vector2> scanPointsInRobotFrame(const Scan& scan, const Pose2& laser_pose,
                                            const ScanMatcherOptions& options);

// A reference normal from the sums over a point's neighbours within the
// normal radius, the point itself included: the principal axis of least
// spread. False with fewer than three points (too few to say whether they
// lie on a line) or without a dominant direction.
bool fitNormal(const Vector2& sum, const Matrix2& sum_sq, int n, Vector2* normal);

// The local map's points with the sums over their neighbourhoods, kept up
// to date as key scans enter (newest) and leave (oldest). The normals are
// those PointCloudReference fits over all the points together; a key scan
// costs the neighbour searches of its own points and of the leaving ones,
// not of the whole map's.
class SlidingNormals {
 public:
  explicit SlidingNormals(double normal_radius);
  void push(const std::vector<Vector2>& points);
  void popOldest();
  size_t scanCount() const { return scans_.size(); }
  // The points that have a normal, oldest key scan first, and the normals.
  void fitted(std::vector<Vector2>* points, std::vector<Vector2>* normals) const;

 private:
  struct Point {
    Vector2 p;
    Vector2 sum = Vector2::Zero();
    Matrix2 sum_sq = Matrix2::Zero();
    int n = 0;
    // The normal fitted from the sums, refitted only after they change.
    mutable bool stale = true;
    mutable bool has_normal = false;
    mutable Vector2 normal = Vector2::Zero();
  };
  using CellKey = long long;
  using Entry = std::pair<long, int>;  // (key scan serial, point index)
  CellKey cellKey(int ix, int iy) const;
  void cellOf(const Vector2& p, int* ix, int* iy) const;
  Point& at(const Entry& e) { return scans_[e.first - front_serial_][e.second]; }
  // Calls f(entry, point) for every point within the normal radius of p.
  template <class F>
  void forNeighbours(const Vector2& p, F f);

  double radius2_;
  double cell_size_;  // the normal radius: its 3 × 3 cells hold every neighbour
  long front_serial_ = 0;
  std::deque<std::vector<Point>> scans_;
  std::unordered_map<CellKey, std::vector<Entry>> grid_;
};

struct ScanMatcherCounters {
  long matched = 0;
  long refused = 0;                // fell back to the odometry increment, for one of three reasons:
  long refused_by_fit = 0;         // too few points, point pairs or inliers
  long refused_by_correction = 0;  // a change of the odometry guess beyond max_correction_*
  long refused_by_odometry = 0;    // the check against the wheels
  long unchecked_by_odometry = 0;  // matches not checked: stamp not after the previous scan's
  long key_scans = 0;
};

// The front end used by the pipeline: keeps a local map of the last key
// scans in its own "scan-matched odometry" frame and turns every raw
// odometry pose into a corrected one. A refused match (too few pairs, a
// correction beyond the bounds) falls back to the odometry increment, so
// the output is never worse than dead reckoning by more than one refusal.
// What a later run continues from (a saved SLAM state): the corrected
// pose, the raw odometry there, and the global map with its normals.
struct ScanMatchingOdometryState {
  Pose2 last_raw;
  Pose2 last_corrected;
  Pose2 last_key_pose;
  double last_stamp = 0.0;
  std::vector<Vector2> map_points, map_normals;
};

class ScanMatchingOdometry {
 public:
  // `wheel_noise`: the noise model of the raw odometry increment, for the
  // check against the wheels (the filter's motion noise in the thesis's mode).
  explicit ScanMatchingOdometry(const ScanMatcherOptions& options,
                                const MotionNoiseOptions& wheel_noise = MotionNoiseOptions());

  // Corrected odom → base_link for this scan. `laser_pose` is base_link → laser.
  Pose2 process(const Scan& scan, const Pose2& raw_odometry, const Pose2& laser_pose,
                MatchResult* result = nullptr);
  // The same for the scan's points in the robot frame as
  // scanPointsInRobotFrame gives them with this matcher's options, taken
  // at `stamp` (two matchers of one scan share them).
  Pose2 processPoints(const std::vector<Vector2>& points, double stamp, const Pose2& raw_odometry,
                      MatchResult* result = nullptr);

  // The corrected pose of a scan that cannot be matched (bad geometry):
  // the last corrected pose moved by the raw odometry increment. No state change.
  Pose2 deadReckon(const Pose2& raw_odometry) const {
    return initialised_ ? compose(last_corrected_, between(last_raw_, raw_odometry)) : raw_odometry;
  }

  // True when the raw odometry moved from the last scan's by more than
  // max_translation (m) or turned by more than max_rotation (rad): the
  // filter's jump rule (a corrupt sample, a driver reset), applied to the
  // raw increment before it becomes the match's guess.
  bool isOdometryJump(const Pose2& raw_odometry, double max_translation, double max_rotation) const;
  // Discards the raw increment since the last scan: the next scan starts
  // from `raw_odometry` with the corrected pose where it was.
  void reanchorRaw(const Pose2& raw_odometry) {
    if (initialised_) last_raw_ = raw_odometry;
  }

  const ScanMatcherCounters& counters() const { return counters_; }
  size_t mapPoints() const { return reference_ ? reference_->size() : 0; }

  // The global map's matcher after its first scan: its state to continue
  // from, else none (a local map is not kept: it refills in a few scans).
  std::optional<ScanMatchingOdometryState> state() const;
  // Goes on from `state`: the next scan is matched against its map, its
  // raw odometry taken from state.last_raw (a jump when the odometry
  // restarted: see FrontEnd). False, and nothing changed, for a local map.
  bool restore(const ScanMatchingOdometryState& state);

 private:
  void addKeyScan(const std::vector<Vector2>& points, const Pose2& pose);
  bool globalMap() const { return options_.map_mode == "global"; }
  // Squared Mahalanobis distance between the matched and the odometry
  // increments (both from the last scan), under the wheel noise.
  double odometryDisagreement(const Pose2& raw_odometry, const Pose2& matched, double dt) const;

  ScanMatcherOptions options_;
  MotionNoiseOptions wheel_noise_;
  double odometry_gate_ = 0.0;  // χ²₃ quantile; 0: no check
  ScanMatcherCounters counters_;
  bool initialised_ = false;
  int consecutive_refusals_ = 0;
  Pose2 last_raw_;
  double last_stamp_ = 0.0;  // of the last scan processed
  Pose2 last_corrected_;
  Pose2 last_key_pose_;
  SlidingNormals local_map_;  // local mode: the last key scans, in the corrected frame
  std::optional<PointCloudReference> reference_;  // the map matched against
};

}  // namespace ekf_slam
