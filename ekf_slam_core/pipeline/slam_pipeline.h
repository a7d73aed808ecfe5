// The whole SLAM system behind one object: a laser scan and the robot's
// odometry pose at the scan's stamp go in; every scan gets a pose in the
// map frame. The live ROS node, the offline bag runner and the tests call
// this same object, so a bag gives the same answer live and offline.
//
// SlamPipeline coordinates four stages, each owning its part of the state:
//   FrontEnd     the control source: raw or scan-matched odometry (front_end.h);
//   LocalFilter  the EKF with its landmark strategies (lines, MECP, rooms)
//                and the map's maintenance (local_filter.h);
//   BackEndLink  the loop-closing pose graph and the causal estimate it
//                gives, re-anchoring the filter after loops (back_end_link.h);
//   ScanHistory  one bounded history of the scans and iterations, read by
//                the smoothers and the trajectory writers (scan_history.h).
// A scan record moves front end → filter → back end → history; the
// coordinator itself only decides whether a scan is iterated.
//
// Frames: `odometry` is odom → base_link from the robot (never corrected,
// thesis §3.4.2); the filter estimates map → base_link; map → odom follows.
// The laser pose on the robot (base_link → laser) is in options.filter.
//
// Policies for imperfect input, each counted in PipelineCounters:
// - The first scan initialises the map (no prediction).
// - A stamp not after the last iteration's (logs whose time goes backwards,
//   duplicates): no iteration; the scan still gets a dead-reckoned pose.
// - Less motion than min_travel_* since the last iteration: no iteration
//   (the thesis iterates after each discrete motion); dead-reckoned pose.
// - An odometry increment beyond the filter's jump bounds: the increment is
//   discarded (the odometry is re-anchored), no iteration.
// - A scan whose geometry is unusable (or features with non-finite values):
//   no iteration, pose dead-reckoned.
// - An odometry pose that is not finite or lies beyond kMaxOdometryCoordinate
//   from the odometry origin: no iteration, counted as bad input.
#pragma once

#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/pipeline/back_end_link.h"
#include "ekf_slam_core/pipeline/front_end.h"
#include "ekf_slam_core/pipeline/local_filter.h"
#include "ekf_slam_core/pipeline/pipeline_options.h"
#include "ekf_slam_core/pipeline/scan_history.h"
#include "ekf_slam_core/pipeline/scan_result.h"
#include "ekf_slam_core/pipeline/slam_state.h"
#include "ekf_slam_core/pipeline/smoothing_problem.h"

namespace ekf_slam {

// What became of the scans (the coordinator's own counts).
struct ScanCounters {
  long scans = 0;
  long iterations = 0;
  long skipped_no_motion = 0;
  long time_not_increasing = 0;
  long odometry_jumps = 0;
  long accepted_large_moves = 0;  // increments beyond the jump bounds after acceptNextMotion()
  long bad_input = 0;
};

// Every stage's counts, for reports and diagnostics.
struct PipelineCounters : ScanCounters, FrontEndCounters, FilterCounters {};

// A value: every stage is one (the front end's matchers, the filter's state
// with its strategies, the back end's graph and views, the history), so a
// copy is a snapshot of everything the pipeline knows and continues exactly
// as the original would. Copying waits for a back end on its own thread to
// process the scans handed to it; it must not race processScan.
class SlamPipeline {
 public:
  // Options must be valid (check validate()).
  explicit SlamPipeline(const PipelineOptions& options);

  // `odometry` is the robot's raw odom → base_link at the scan's stamp.
  ScanResult processScan(const Scan& scan, const Pose2& odometry);

  // The same iteration from features already extracted from a scan (for
  // example by a separate feature node): `features` in the laser frame, as
  // extractFeatures gives them; `stamp` the scan's stamp. Only the point
  // features that are landmark candidates are used, as in processScan, so
  // extractFeatures(scan) in gives bit-identical results. Scan matching and
  // loop closure need the scan itself: with either enabled the input is
  // rejected.
  ScanResult processFeatures(double stamp, const FeatureSet& features, const Pose2& odometry);

  // The next iteration's odometry increment is a move that was made, not a
  // jump, however large: the robot was driven while SLAM was paused (the
  // node's ~resume and ~step, the supervised step mode). The front end and
  // the filter take it as control; it is counted (accepted_large_moves when
  // it exceeds the jump bounds).
  void acceptNextMotion() { accept_next_motion_ = true; }

  // Everything a later run needs to go on mapping (slam_state.h); waits for
  // a back end on its own thread. `configuration`: the options as text,
  // kept in the state for people.
  SlamState state(const std::string& configuration = "") const;
  // Goes on from `state`, before the first scan: the filter's map and pose,
  // the loop closer's key scans and graph, the history (the trajectories
  // and smoothers then cover the saved scans too). The next scan is taken where the
  // saved run stopped (its odometry may start anywhere: only increments
  // count). Refused, with the reason, after the first scan, or when the
  // laser mount differs from options.filter.laser_pose (the key scans'
  // readings hang off it) by more than 1 cm or 0.5 degrees.
  // ResumeAt::kPlacedRobot: the robot was moved in the state (placeRobot,
  // global_localization.h), so the first new scan hangs where it was put
  // even where the front end goes on on its saved map.
  std::string resume(const SlamState& state, ResumeAt at = ResumeAt::kWhereItStopped);

  // The stages, read-only.
  const FrontEnd& frontEnd() const { return front_end_; }
  const LocalFilter& localFilter() const { return filter_; }
  const BackEndLink& backEnd() const { return back_end_; }
  const ScanHistory& history() const { return history_; }

  const EkfSlam& filter() const { return filter_.filter(); }
  // For seeding a prior map (EkfSlam::addLandmark) and switching to
  // localisation only, before or between scans; not during processScan.
  EkfSlam& mutableFilter() { return filter_.mutableFilter(); }
  const PipelineOptions& options() const { return options_; }
  PipelineCounters counters() const;
  // The kept history (options.history_scans; see ScanHistory).
  const std::vector<ScanRecord>& scans() const { return history_.records(); }
  const TrajectoryRecorder& iterations() const { return history_.iterations(); }
  const FullSmootherRecorder& smootherRecord() const { return history_.smootherRecord(); }
  long firstScan() const { return history_.firstScan(); }
  long recordedScans() const { return history_.recordedScans(); }
  int firstIteration() const { return history_.firstIteration(); }
  // Per line landmark id: the stretch of the line seen so far and, for a
  // θ-only landmark, its endpoint point landmarks. Empty with points only.
  const std::unordered_map<int, LineSupport>& lineSupport() const { return filter_.lineSupport(); }
  // The extents and endpoint ids of line landmarks seeded into the filter
  // from a map file (before the first scan); ignored without lines.
  void seedLineSupport(const std::unordered_map<int, LineSupport>& support) {
    filter_.seedLineSupport(support);
  }
  // rooms.enabled: the rooms of the last rebuild and the landmarks' labels;
  // null before the first rebuild that found a map (association ungated).
  const RoomGate* roomGate() const { return filter_.roomGate(); }

  // map → odom, so that map → odom → base_link is the estimate at the last
  // iteration, with odom → base_link the robot's raw odometry.
  Pose2 mapToOdom() const;

  // Poses for every kept scan from the full smoother's iteration poses
  // (SmoothingProblem::solve). Runs the batch optimisation on every call;
  // `details` (if given) receives its result, `last_problem` (if given) the
  // problem of its last optimisation (see smoothFull).
  std::vector<StampedPose> smoothedScanPoses(FullSmootherResult* details = nullptr,
                                             LandmarkGraph* last_problem = nullptr) const;
  // The full smoother's problem as a copy (it waits for the back end's
  // thread): to be solved elsewhere while the pipeline goes on.
  SmoothingProblem smoothingProblem() const;
  std::vector<StampedPose> rtsScanPoses() const { return history_.rtsScanPoses(); }
  std::vector<StampedPose> filteredScanPoses() const { return history_.filteredScanPoses(); }
  // ScanRecord::causal for every scan: what a live run publishes.
  std::vector<StampedPose> causalScanPoses() const { return history_.causalScanPoses(); }

  // The back end's key scans as the last scan saw them (loop-closed, map
  // frame), with their readings in the robot frame: for a live occupancy
  // grid and the loop-closed path. Empty without loop closure.
  using KeyScan = BackEndLink::KeyScan;
  std::vector<KeyScan> keyScans(bool with_points) const { return back_end_.keyScans(with_points); }
  // Optimisations the back end has run: a change means new key-scan poses.
  long backEndOptimisations() const { return back_end_.optimisations(); }
  LoopClosureCounters backEndCounters() const { return back_end_.counters(); }
  // Scans handed to the back end that it has not processed yet (its own
  // thread only; inline it is always 0).
  long backEndBacklog() const { return back_end_.backlog(); }

  // Loop closure (options.loop_closure.enabled): finishLoopClosure() runs
  // the final optimisation after the last scan; optimizedScanPoses() then
  // gives one pose per scan in the map frame (empty when loop closure is
  // off).
  void finishLoopClosure() { back_end_.finish(); }
  std::vector<StampedPose> optimizedScanPoses() const { return back_end_.optimizedScanPoses(); }
  // The loop closer itself, once it has processed every scan (waits for
  // the back end's thread); null without loop closure.
  const LoopCloser* loopCloser() const { return back_end_.loopCloser(); }

 private:
  // One input: a scan (features extracted here) or features extracted
  // elsewhere; exactly one of the two is non-null.
  ScanResult process(double stamp, const Scan* scan, const FeatureSet* features,
                     const Pose2& raw_odometry);
  // Why the input cannot be used (empty: it can).
  std::string inputError(const Scan* scan, const FeatureSet* features) const;
  // The first scan after a resume: when it continues the saved run (see
  // SlamState::last_stamp), the last iteration becomes the saved one.
  void continueFromSave(double stamp, const Pose2& raw_odometry, const Pose2& odometry);
  // A scan with unusable input: a dead-reckoned pose, recorded when possible.
  void rejectInput(double stamp, const Scan* scan, const Pose2& odometry,
                   const std::string& input_error, ScanResult* out);
  // A scan that is not iterated: the dead-reckoned pose and covariance.
  void deadReckon(const Pose2& odometry, ScanResult* out) const;
  void iterate(double stamp, const Scan* scan, const FeatureSet* features, const Pose2& odometry,
               bool predict, double dt, ScanResult* out);
  // The prediction; false (and `out` says why) when the filter refused it.
  bool predict(double stamp, const Pose2& odometry, double dt, ScanResult* out);
  // The filter iterated or was re-anchored at this scan.
  void anchorAt(double stamp, const Pose2& odometry);
  // The scan's record: through the back end (the causal estimate), then
  // into the history.
  void record(double stamp, const Scan* scan, const Pose2& odometry, bool usable, ScanResult* out);

  PipelineOptions options_;
  FrontEnd front_end_;
  LocalFilter filter_;
  BackEndLink back_end_;
  ScanHistory history_;
  ScanCounters counters_;
  bool initialised_ = false;
  Pose2 last_odometry_;              // control-source pose at the last iteration (or re-anchor)
  Pose2 last_raw_odometry_;          // the robot's raw odometry at that iteration
  Pose2 current_raw_odometry_;       // the raw odometry of the scan being processed
  double last_stamp_ = 0.0;          // of the last iteration
  bool accept_next_motion_ = false;  // acceptNextMotion(): no jump rule at the next iteration
  long resumed_scans_ = 0;           // scans of the runs before a resume (SlamState::scans)
  // A resumed state's last iteration (stamp, raw odometry), until the first scan.
  std::optional<std::pair<double, Pose2>> resume_from_;
};

}  // namespace ekf_slam
