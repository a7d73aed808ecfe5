// Full smoother: the batch maximum-a-posteriori estimate of every robot pose
// the filter had and every landmark it ever held, over exactly the
// information the EKF used (GraphSLAM over the filter's own decisions;
// derivation in docs/maths.md §8).
//
// The RTS smoother (rts_smoother.h, thesis §3.4.5.1) runs backwards over the
// pose marginals alone and drops the pose–landmark correlations, so a
// landmark re-seen late cannot move the early poses through the map. Here
// the landmarks are unknowns too, and the estimate is the minimum of
//   Σ_k ‖motion_k‖²_Σk + Σ_obs ρ(‖z − h(x_k, m_j)‖²_R) + ‖prior‖² (+ loops)
// with
// - nodes: the pose of every filter iteration, every landmark the filter
//   created (a merged landmark's sightings go to the survivor; pruned
//   landmarks keep theirs);
// - motion edges: each iteration's control u_k with the filter's Q(u_k),
//   carried into the pose space by G (Σ_k = A G₀ Q G₀ᵀ Aᵀ, see the maths note);
// - wheel edges (a scan-matched control): each step's wheel increment, with
//   the wheels' noise learned from the run (FullSmootherOptions::wheel_edges);
// - observation edges: each observation the filter matched or made a
//   landmark from, with the feature's range–bearing covariance, through the
//   laser mount; optionally with a robust kernel;
// - the prior on the first pose (held fixed when its covariance is zero,
//   as in the shipped configurations);
// - optional relative-pose edges (the loop closures of the back end).
// Initialised from the filtered estimates and solved by Levenberg–Marquardt
// (pose_graph/landmark_graph.h). The filter's data-association decisions
// are taken as given: the smoother does not re-associate.
#pragma once

#include <unordered_map>
#include <vector>

#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/pose_graph/landmark_graph.h"

namespace ekf_slam {

// What a motion edge of the full smoother measures.
enum class SmootherMotion {
  kControl,     // the filter's control (the control source's increment)
  kLocalMatch,  // the scan matcher against the last key scans alone
};

// Which smoother gives a run's smoothed trajectory.
enum class SmootherMethod {
  kFull,  // the batch smoother below: every pose, landmark, sighting and loop
  kRts,   // the thesis's Rauch-Tung-Striebel pass over the pose alone (§3.4.5)
};

struct FullSmootherOptions {
  // kRts: the smoothed trajectory (the offline trajectory_smoothed.txt and
  // its map, the live ~smooth) is the RTS pass over the filter's recorded
  // pose steps, and the options below are not used.
  SmootherMethod method = SmootherMethod::kFull;

  // Motion edges. With a global-map front end (scan_matching.map_mode:
  // global) the control is each scan matched against every key scan so
  // far; where that map holds an old mistake (a stall in a corridor, a
  // wall drawn twice) the match carries it, and over a few scans it is
  // worse than a match against the last key scans alone (relations under
  // 5 s: Intel 0.021 against 0.012 m, ACES 0.039 against 0.034 m,
  // docs/offline.md). kLocalMatch runs that second, local matcher beside
  // the front end (scan_matching's settings, map_mode local, the last
  // local_match_key_scans key scans) and takes its increment as each
  // motion edge's measurement, with the control's covariance; the long
  // range stays with the loops and the landmarks. It costs a second scan
  // match per scan. The control is used when scan matching is off or
  // already local.
  SmootherMotion motion_edges = SmootherMotion::kLocalMatch;
  // Key scans in the local matcher's map (scan_matching.keyscan_distance
  // apart: 4 hold about the last 0.6 m). 4 and 8 give the logs' final
  // errors within 1.4 mm of each other; 4 costs less.
  int local_match_key_scans = 4;
  // Wheel edges. When the control is a scan match, the wheels measured
  // each step too, independently of the laser, and a building where the
  // laser sees little (outdoors, long corridors) is where the match drifts
  // and the wheels may not (the hospital log: scan-matched heading 12.5°
  // off across visits minutes apart, the wheels 1.6°). Each step then gets
  // a second motion edge, the wheels' increment. How far to trust the
  // wheels is learned from the run itself, not assumed: their
  // disagreement with the motion edges' measurement, per metre driven,
  // gives each axis's variance (robustly: the median of r²/d over the
  // steps, divided by the median of χ²₁, 0.455). That spread holds the
  // matcher's noise too, so the wheels are never weighted above what the
  // data show of them. Wheels that slip or a bump are heavy-tailed
  // errors: a Cauchy kernel (kernel_width) takes those out. Steps where
  // the motion edge is the wheels' increment already (the match fell back
  // to them) get no second edge.
  bool wheel_edges = true;
  RobustKernel wheel_kernel = RobustKernel::kCauchy;
  // Kernel on observation edges: a wrong association (a corner matched to
  // its neighbour) is down-weighted instead of bending the trajectory.
  // Cauchy beat Huber and no kernel on every simulated bag.
  RobustKernel observation_kernel = RobustKernel::kCauchy;
  // Loop-closure edges (Cauchy, as in the back end).
  RobustKernel loop_kernel = RobustKernel::kCauchy;
  // kernel_width (sigmas) applies to both kernels. The returned solve runs
  // until a step lowers the cost by less than 10⁻⁵ of it, at most 100 LM
  // steps (the verification rounds' solves stop earlier, below): far
  // below the cost's own spread (√(2·dof), about 0.5 % of it on Intel), and
  // the logs' trajectories equal those at 10⁻⁶ to 0.1 mm in 45 % of the
  // steps (docs/offline.md, "Solve tolerances"). With the re-association
  // below, the answer no longer depends on the cap; before it, more steps slid the estimate along a
  // flat valley that the filter's wrong associations shaped, and an early stop was needed.
  LandmarkGraphOptions optimizer = defaultOptimizer();
  static LandmarkGraphOptions defaultOptimizer() {
    LandmarkGraphOptions o;
    o.max_iterations = 100;
    o.min_relative_decrease = 1e-5;
    return o;
  }
  // Verification of the associations (the filter's, or the re-association's). A landmark's
  // sightings are cut into visits where it was not seen for more than revisit_gap iterations; after
  // the optimisation, a visit whose χ² exceeds the revisit_gate_probability quantile of χ²(2 per
  // sighting) is detached from the landmark (it was matched to the wrong one), and the problem is
  // solved again, at most max_verification_rounds times.
  int revisit_gap = 50;                     // iterations
  double revisit_gate_probability = 0.999;  // χ² quantile
  int max_verification_rounds = 2;          // 0: take every association as given
  // A solve followed by a verification needs each visit's χ², not the last
  // digits of the optimum: it ends once a step lowers the cost by less than
  // this fraction. The solve whose result is returned then runs on from
  // there to the optimizer's own min_relative_decrease (after a round that
  // detached nothing, a last solve of the same problem does that). The long
  // tail of small steps, which the robust kernels make slow, is thus paid
  // once instead of in every round (docs/offline.md, "Solve tolerances").
  // At or below min_relative_decrease every solve runs to it.
  double verification_relative_decrease = 1e-3;

  // Re-association against the initial poses. When smoothFull() is given
  // initial poses (the loop-closed back end's), the filter's associations
  // are dropped and every sighting is associated afresh, in iteration order,
  // against the landmarks the earlier sightings build from those poses: the
  // filter made its decisions from its own, possibly metres-off estimate
  // (Intel: 3.1 m mean relation error against 0.04 m for the pose graph),
  // and a decision made there is not evidence the batch should trust.
  // A sighting's map position is uncertain by its own covariance plus the
  // initial pose's, taken as reassociation_position_sigma (m, per axis) and
  // reassociation_heading_sigma (rad): the accuracy expected of the
  // loop-closed poses. Gate: the reassociation_gate_probability quantile of
  // χ²(2); one sighting per landmark and iteration; a sighting inside the
  // gate of two landmarks is left out (ambiguous).
  bool reassociate = true;
  double reassociation_position_sigma = 0.05;  // m
  double reassociation_heading_sigma = 0.01;   // rad
  double reassociation_gate_probability = 0.99;

  // The optimizer's fields sit in the smoother's own section.
  template <class Visitor>
  void visitFields(Visitor& v) {
    const Choices<RobustKernel> kernels = {{RobustKernel::kNone, "none"},
                                           {RobustKernel::kHuber, "huber"},
                                           {RobustKernel::kCauchy, "cauchy"}};
    v.choice("method", method, {{SmootherMethod::kFull, "full"}, {SmootherMethod::kRts, "rts"}});
    v.choice("motion_edges", motion_edges,
             {{SmootherMotion::kControl, "control"}, {SmootherMotion::kLocalMatch, "local_match"}});
    v.integer("local_match_key_scans", local_match_key_scans, Bounds::closed(1, 1000, "scans"));
    v.flag("wheel_edges", wheel_edges);
    v.choice("wheel_kernel", wheel_kernel, kernels);
    v.choice("observation_kernel", observation_kernel, kernels);
    v.choice("loop_kernel", loop_kernel, kernels);
    optimizer.visitFields(v);
    v.integer("revisit_gap", revisit_gap, Bounds::closed(1, 1e8, "iterations"));
    v.number("revisit_gate_probability", revisit_gate_probability, Bounds::open(0.0, 1.0));
    v.integer("max_verification_rounds", max_verification_rounds, Bounds::closed(0, 100));
    v.number("verification_relative_decrease", verification_relative_decrease,
             Bounds::closed(0.0, 1.0));
    v.flag("reassociate", reassociate);
    v.number("reassociation_position_sigma", reassociation_position_sigma,
             Bounds::closed(0.0, 100.0, "m"));
    v.number("reassociation_heading_sigma", reassociation_heading_sigma,
             Bounds::closed(0.0, kPi, "rad"));
    v.number("reassociation_gate_probability", reassociation_gate_probability,
             Bounds::open(0.0, 1.0));
  }

  std::string validate() const;  // empty when valid, else names the bad field
};

struct LandmarkSighting {
  int landmark_id = -1;  // as the filter named it at the time (before any merge)
  PointObservation observation;
};

// What one filter iteration used.
struct SmootherIteration {
  double stamp = 0.0;  // s
  Pose2 filtered;      // x_k|k, the initial guess
  bool has_control = false;
  OdometryControl control;                       // u_k: from the previous iteration to this one
  Matrix3 control_covariance = Matrix3::Zero();  // Q(u_k) the filter used
  // The motion edge's measurement: the same move as measured by the
  // local-map scan matcher when the pipeline runs one (its short-range
  // shape is not bent by the global map's mistakes), else u_k itself.
  // Its covariance is u_k's.
  Pose2 motion;
  // The wheels' own increment over the same step, when the control is
  // not the wheels (a scan match) and the step is no odometry jump.
  bool has_wheels = false;
  Pose2 wheels;
  std::vector<LandmarkSighting> sightings;
};

// A relative-pose constraint between two iterations' poses, each carried by
// a constant offset (a key scan = its iteration's pose ⊕ the odometry since).
struct IterationConstraint {
  int from_iteration = 0;
  int to_iteration = 0;
  Pose2 from_offset;
  Pose2 to_offset;
  Pose2 measurement;  // (to ⊕ to_offset) in the frame of (from ⊕ from_offset)
  Matrix3 information = Matrix3::Identity();
};

// Records the forward run: one addIteration() per filter iteration, after
// its update, augmentation, pruning and merges.
class FullSmootherRecorder {
 public:
  void setPrior(const Pose2& mean, const Matrix3& covariance);
  // `control` is null on the initialising iteration (no prediction).
  // `local_motion`, when not null, is the motion edge's measurement
  // (SmootherIteration::motion); else the control is. `wheels`, when not
  // null, is the wheels' increment over the step (SmootherIteration::wheels).
  void addIteration(double stamp, const EkfSlam& filter, const OdometryControl* control,
                    const std::vector<PointObservation>& observations,
                    const IterationReport& report, const Pose2* local_motion = nullptr,
                    const Pose2* wheels = nullptr);

  // Forgets the oldest `count` iterations (a bounded history), and the
  // merges and landmark estimates only they referred to. The caller gives
  // the new first iteration its prior (setPrior): the smoother then starts
  // there, as from the first pose of a run.
  void dropFront(size_t count);

  const std::vector<SmootherIteration>& iterations() const { return iterations_; }
  // Goes on from a record saved earlier (a resumed run, slam_state.h):
  // its iterations, merges (dropped id → kept id), the landmark estimates
  // and the first iteration's prior.
  void restore(std::vector<SmootherIteration> iterations, std::unordered_map<int, int> merged_into,
               std::unordered_map<int, Vector2> last_estimates, const Pose2& prior_mean,
               const Matrix3& prior_covariance);

  // The landmark a sighting of `id` belongs to after all merges so far.
  int survivorOf(int id) const;
  // The merges so far: dropped id → the id it went into.
  const std::unordered_map<int, int>& mergedInto() const { return merged_into_; }
  // The filter's estimate of `id` when it was last matched or created.
  const std::unordered_map<int, Vector2>& lastEstimates() const { return last_estimate_; }
  const Pose2& priorMean() const { return prior_mean_; }
  const Matrix3& priorCovariance() const { return prior_covariance_; }

 private:
  std::vector<SmootherIteration> iterations_;
  std::unordered_map<int, int> merged_into_;  // dropped id → kept id
  std::unordered_map<int, Vector2> last_estimate_;
  Pose2 prior_mean_;
  Matrix3 prior_covariance_ = Matrix3::Zero();
};

// The wheels' noise as a run shows it (FullSmootherOptions::wheel_edges):
// a random walk, variance per metre driven on each axis of the step (x
// forward, y left, heading).
struct WheelNoise {
  int samples = 0;                                 // steps it was learned from
  Vector3 sigma_per_sqrt_metre = Vector3::Zero();  // m/√m, m/√m, rad/√m
  int edges = 0;                                   // wheel edges added
};

// Learns WheelNoise from the recorded steps that have both a motion edge
// and the wheels' increment, and where the two differ. A step counts at
// least kWheelMinStep of travel (a turn on the spot). Fewer than
// kWheelMinSamples such steps: samples is that count and sigma zero (too
// little to learn from; no wheel edges).
constexpr double kWheelMinStep = 0.01;  // m
constexpr int kWheelMinSamples = 30;
WheelNoise learnWheelNoise(const std::vector<SmootherIteration>& iterations);

struct FullSmootherResult {
  std::vector<Pose2> poses;                    // one per recorded iteration
  std::unordered_map<int, Vector2> landmarks;  // by surviving id (re-associated: by new id)
  int observation_edges = 0;
  int constraint_edges = 0;
  int detached_visits = 0;       // visits the verification took from their landmark
  bool reassociated = false;     // the sightings were associated afresh (landmark ids are new)
  int ambiguous_sightings = 0;   // left out by the re-association
  LandmarkGraphSummary summary;  // iterations summed over the verification rounds
  WheelNoise wheels;             // learned for the wheel edges (edges = 0: none added)
};

// `filter` gives the laser mount and the final landmark estimates, the
// initial guess together with the filtered poses. `initial_poses` (one per
// iteration, optional) replaces the filtered poses as the initial guess;
// each landmark then starts at the median of its sightings projected from
// them, and with options.reassociate the sightings are associated afresh
// against those poses. Constraints referring to unknown iterations are
// ignored. `last_problem` (optional) receives the last optimisation's
// problem as it started (initial values included), to be saved and solved
// again elsewhere (graph_io.h); the result does not depend on it.
FullSmootherResult smoothFull(const FullSmootherRecorder& record, const EkfSlam& filter,
                              const std::vector<IterationConstraint>& constraints,
                              const FullSmootherOptions& options,
                              const std::vector<Pose2>* initial_poses = nullptr,
                              LandmarkGraph* last_problem = nullptr);

// The pose-space covariance of a motion edge's error
// between(d, between(x_{k−1}, x_k)), d = applyControl(identity, u), for
// control noise Q: A G₀ Q G₀ᵀ Aᵀ with G₀ = ∂d/∂u and A = diag(R(d_θ)ᵀ, 1),
// plus a small floor (G₀ is singular for a turn on the spot).
Matrix3 motionEdgeCovariance(const OdometryControl& u, const Matrix3& control_covariance);

}  // namespace ekf_slam
