// The whole SLAM front- and back-end behind one object: a laser scan and the
// robot's odometry pose at the scan's stamp go in; features are extracted,
// the EKF iterates, and every scan gets a pose in the map frame. The live ROS
// node, the offline bag runner and the tests call this same object, so a bag
// gives the same answer live and offline.
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

#include <deque>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/loop_closure/back_end.h"
#include "ekf_slam_core/loop_closure/loop_closer.h"
#include "ekf_slam_core/mecp/room_gating.h"
#include "ekf_slam_core/pipeline/line_landmarks.h"
#include "ekf_slam_core/scan_matching/scan_matcher.h"
#include "ekf_slam_core/smoother/full_smoother.h"
#include "ekf_slam_core/smoother/rts_smoother.h"

namespace ekf_slam {

constexpr double kMaxOdometryCoordinate = 1e6;  // m: no robot drives 1,000 km from its origin

// An odometry pose the pipeline can use: finite and within
// kMaxOdometryCoordinate of the odometry origin (a corrupt sample of 1e300 m
// would carry the scan matcher's grids past what an index can hold). A scan
// whose odometry is not usable gets no ScanRecord.
bool usableOdometry(const Pose2& odometry);

// Room gating of the point association (thesis §4.4.5) from the walls the
// filter has mapped: every rebuild_interval iterations the line landmarks'
// sighted stretches are taken as walls, doorways are found among them and
// the free space between them is split into rooms (mecp/doorways.h); each
// point landmark is labelled with the room it was seen from, and an
// observation is associated only with landmarks of its own rooms
// (associateInRooms, mecp/room_gating.h). Needs line landmarks
// (landmarks: points+lines or points+lines_theta).
struct RoomGatingOptions {
  bool enabled = false;
  int rebuild_interval = 20;  // iterations between rebuilds of the rooms
  DoorwayOptions doorways;
  RoomMapOptions map;
  RoomGateOptions gate;

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.flag("enabled", enabled);
    v.integer("rebuild_interval", rebuild_interval, Bounds::closed(1, 1e6, "iterations"));
    v.section("doorways", doorways);
    v.section("map", map);
    v.section("gate", gate);
  }
};

struct PipelineOptions {
  FeatureOptions features;
  FilterOptions filter;
  AssociationOptions association;
  // The robot's pose in the map frame at the first scan, and its
  // covariance: the origin and certain by default (the map frame is the
  // first pose); a pose in a loaded map for localisation (load_map,
  // /initialpose).
  Pose2 initial_pose;
  Matrix3 initial_pose_covariance = Matrix3::Zero();
  // Run the loop-closing back end on a thread of its own (a live node:
  // scan processing never waits for a loop search or an optimisation,
  // unless loop_closure.correction_delay asks it to); false: inline, as the
  // offline runner does. Not a file setting: the program decides.
  bool back_end_thread = false;
  // History kept for the smoothers and the trajectories: 0 keeps every scan
  // (the offline runner writes one pose per scan of the whole log); n > 0
  // keeps at least the newest n scans (trimmed in steps of n / 8, so at
  // most 9n/8) with the iterations they hang off, so that memory stops
  // growing with the time a live node runs. The oldest kept iteration then
  // takes the place of the first pose for the full smoother: its prior is
  // the filter's pose and covariance at that iteration (with loop closure,
  // its loop-closed pose). The causal estimate never reads the history, so
  // the poses a scan is given do not depend on n. Not a file setting: the
  // program decides (the node's history_max_scans).
  long history_scans = 0;
  double min_travel_distance = 0.0;  // m: iterate only after this much translation …
  double min_travel_angle = 0.0;     // rad: … or this much rotation (both 0: every scan)
  double max_landmark_range = 20.0;  // m: farther point features are not used
  // m: nearer point features are not used either. Close by, a landmark's
  // few centimetres of error are degrees of bearing, and the update's
  // first-order model turns them into heading error it does not account for
  // (docs/results.md, "the pose NEES"). 0: no limit.
  double min_landmark_range = 0.0;
  // Map management: a landmark matched fewer than prune_min_observations
  // times (its creation included) once prune_age_steps iterations old is
  // removed. Corners of people, chairs and doors that moved are seen a few
  // times and never again, yet each costs O(n) per update forever.
  int prune_min_observations = 4;  // 0: keep every landmark that survived tentative pruning
  long prune_age_steps = 100;      // iterations a landmark has to gather its observations
  // The filter's landmark set is bounded: beyond max_landmarks, those
  // matched least recently are marginalised out of the filter (their rows
  // and columns dropped: exact for a Gaussian). The loop-closing back end
  // and the full smoother keep their sightings, so the map and the final
  // trajectory still use them; the filter's cost per scan stops growing
  // with the building (an iteration at 100 landmarks: about 0.1 ms). 0:
  // no bound.
  int max_landmarks = 100;
  // Which features become landmarks: the point features alone, or also the
  // extractor's wall segments as (p, θ) lines or as θ-only lines whose
  // offset comes from the point landmarks at their ends (line_landmarks.h).
  // Lines share the points' association gates and pruning policy, and the
  // landmark bound.
  LandmarkSet landmarks = LandmarkSet::kPoints;
  LineLandmarkOptions lines;
  RoomGatingOptions rooms;
  // Control source. With scan_matching.enabled every scan is first aligned to
  // the last key scans (ScanMatchingOdometry) and the scan-matched pose takes
  // the place of the raw odometry pose everywhere below: the filter's control
  // is then the scan-matched increment, with scan_matched_motion_noise as its
  // noise. Disabled: the raw odometry increment with filter.motion_noise
  // (the thesis's mode).
  ScanMatcherOptions scan_matching;
  MotionNoiseOptions scan_matched_motion_noise = defaultScanMatchedMotionNoise();
  // Loop-closing back end (pose graph over key scans) fed with the control
  // source's poses; its trajectory is optimizedScanPoses().
  LoopClosureOptions loop_closure;
  // The full smoother (batch MAP over every pose, landmark and observation
  // the filter used, plus the loop closures when on): smoothedScanPoses().
  FullSmootherOptions smoother;

  // Noise of a scan-matched increment: a few millimetres and a tenth of a
  // degree per step, growing slowly with the motion (docs/offline.md).
  // The pipeline's own numbers. The nested options (features, filter, …)
  // check themselves in validate() and are the configuration's sections;
  // initial_pose and its covariance are checked there too.
  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("min_travel_distance", min_travel_distance, Bounds::atLeast(0.0, "m"));
    v.number("min_travel_angle", min_travel_angle, Bounds::closed(0.0, 2.0 * kPi, "rad"));
    v.number("max_landmark_range", max_landmark_range, Bounds::above(0.0, "m"));
    v.number("min_landmark_range", min_landmark_range, Bounds::atLeast(0.0, "m"));
    v.integer("prune_min_observations", prune_min_observations, Bounds::closed(0, 1e6));
    v.integer("prune_age_steps", prune_age_steps, Bounds::closed(1, 1e8, "iterations"));
    v.integer("max_landmarks", max_landmarks, Bounds::closed(0, 1e6));
    v.choice("landmarks", landmarks,
             {{LandmarkSet::kPoints, "points"},
              {LandmarkSet::kPointsAndLines, "points+lines"},
              {LandmarkSet::kPointsAndLineAngles, "points+lines_theta"},
              {LandmarkSet::kPointsAndMecp, "points+mecp"}});
    v.section("lines", lines);
    v.section("rooms", rooms);
  }

  static MotionNoiseOptions defaultScanMatchedMotionNoise();

  std::string validate() const;  // empty when valid, else names the bad field
};

enum class ScanOutcome {
  kIterated,         // predict + update (or the initialising first scan)
  kSkippedNoMotion,  // below min_travel_*
  kSkippedTimeNotIncreasing,
  kRejectedOdometryJump,
  kRejectedBadInput,  // unusable scan geometry or non-finite odometry
};

const char* toString(ScanOutcome outcome);

struct ScanResult {
  ScanOutcome outcome = ScanOutcome::kIterated;
  Pose2 pose;  // map → base_link at the scan's stamp
  // Covariance of `pose` (x, y, θ): the filter's after an iteration; between
  // iterations the last one's carried through the motion model, as a
  // prediction would carry it, so a dead-reckoned pose is not reported as
  // certain as the iteration it hangs off.
  Matrix3 pose_covariance = Matrix3::Zero();
  // The causal estimate for this scan (ScanRecord::causal): the loop-closed
  // graph's with loop closure on, else `pose`. What a live node publishes.
  Pose2 causal_pose;
  FeatureSet features;                         // what the extractor found (empty when not run)
  std::vector<PointObservation> observations;  // the landmark candidates used
  std::vector<int>
      observation_feature;    // per observation: its index in features.points_of_interest
  IterationReport iteration;  // association, NIS, new landmarks (when iterated)
  LineIterationReport lines;  // the line landmarks' part of it (landmarks other than points)
  std::string message;        // why a scan was not iterated, for the log
};

struct PipelineCounters {
  long scans = 0;
  long iterations = 0;
  long skipped_no_motion = 0;
  long time_not_increasing = 0;
  long odometry_jumps = 0;
  long accepted_large_moves =
      0;  // increments beyond the jump bounds taken after acceptNextMotion()
  long bad_input = 0;
  long update_failures = 0;  // iterations whose update was refused
  long observations = 0;     // landmark candidates offered to the filter
  long matches = 0;
  long ambiguous = 0;  // between the gates, or lost to a better observation
  long new_landmarks = 0;
  long line_observations = 0;  // wall segments offered to the filter (after the length/range gate)
  long line_matches = 0;
  long line_endpoint_matches = 0;  // of those: θ-only, the offset from endpoint points
  long line_ambiguous = 0;
  long new_line_landmarks = 0;
  long lines_refused = 0;         // segments with non-finite values or covariance
  long line_update_failures = 0;  // iterations whose line update was refused
  double line_nis_sum = 0.0;      // over all line matches
  long mecp_updates = 0;          // points+mecp: scans whose MECP updated the filter
  long mecp_without_polygon = 0;  // … whose matched points enclose the robot in none
  long mecp_skipped = 0;          // … whose centre lay too near, or the update was refused
  long pruned = 0;                // tentative landmarks removed
  long pruned_rare = 0;           // landmarks removed by prune_min_observations
  long marginalised = 0;          // landmarks dropped by the max_landmarks bound
  long scan_matches = 0;          // scans aligned by the scan matcher
  long scan_match_refusals = 0;   // scans that fell back to the odometry increment
  // Each scan matcher's own counts, refusals by reason and the matches not
  // checked against the wheels (stamp not increasing): the front end's,
  // and the local matcher's that measures the full smoother's motion edges
  // (smoother.motion_edges: local_match) when it runs.
  ScanMatcherCounters front_end;
  bool local_matcher_runs = false;
  ScanMatcherCounters local_matcher;
  long reanchors = 0;              // times the filter took the loop-closed geometry
  long room_rebuilds = 0;          // rooms.enabled: times the rooms were rebuilt …
  long room_rebuild_failures = 0;  // … and found no usable map (no walls yet, too large)
  int rooms = 0;                   // rooms in the last rebuild (0: no gating now)
  int doorways = 0;                // doorways in the last rebuild
  double nis_sum = 0.0;            // over all matches
};

// One entry per scan, for the trajectory files and the smoother.
struct ScanRecord {
  double stamp = 0.0;
  Pose2 filtered;                        // the pose given for the scan when it was processed
  Matrix3 covariance = Matrix3::Zero();  // ScanResult::pose_covariance of it
  Pose2 odometry;      // odom → base_link at the scan (scan-matched when scan matching is on)
  int iteration = -1;  // number of the iteration this pose hangs off (0: the run's first)
  Pose2 odometry_at_iteration;  // the odometry at that iteration
  // The causal estimate given for the scan when it was processed: with loop
  // closure on, the back end's loop-closed graph as it stood after this
  // scan (corrections take effect at the scan whose key scan produced
  // them), in the map frame; otherwise the filtered pose.
  Pose2 causal;
};

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
  // extractFeatures(scan) in gives bit-identical results. Scan matching needs
  // the scan itself: with scan_matching.enabled the input is rejected.
  ScanResult processFeatures(double stamp, const FeatureSet& features, const Pose2& odometry);

  // The next iteration's odometry increment is a move that was made, not a
  // jump, however large: the robot was driven while SLAM was paused (the
  // node's ~resume and ~step, the supervised step mode). The front end and
  // the filter take it as control; it is counted (accepted_large_moves when
  // it exceeds the jump bounds).
  void acceptNextMotion() { accept_next_motion_ = true; }

  const EkfSlam& filter() const { return filter_; }
  // For seeding a prior map (EkfSlam::addLandmark) and switching to
  // localisation only, before or between scans; not during processScan.
  EkfSlam& mutableFilter() { return filter_; }
  const PipelineOptions& options() const { return options_; }
  const PipelineCounters& counters() const { return counters_; }
  // The kept history (options.history_scans): records of scans firstScan()
  // to recordedScans() − 1, and the iterations from firstIteration() on
  // (ScanRecord::iteration counts from the first iteration of the run).
  const std::vector<ScanRecord>& scans() const { return records_; }
  const TrajectoryRecorder& iterations() const { return recorder_; }
  const FullSmootherRecorder& smootherRecord() const { return full_recorder_; }
  long firstScan() const { return first_record_; }
  long recordedScans() const { return first_record_ + static_cast<long>(records_.size()); }
  int firstIteration() const { return first_iteration_; }
  // Per line landmark id: the stretch of the line seen so far and, for a
  // θ-only landmark, its endpoint point landmarks. Empty with points only.
  const std::unordered_map<int, LineSupport>& lineSupport() const;
  // The extents and endpoint ids of line landmarks seeded into the filter
  // from a map file (seedFilter, before the first scan); ignored when the
  // pipeline uses no lines.
  void seedLineSupport(const std::unordered_map<int, LineSupport>& support);
  // rooms.enabled: the rooms of the last rebuild and the landmarks' labels;
  // null before the first rebuild that found a map (association ungated).
  const RoomGate* roomGate() const { return room_gate_.get(); }

  // map → odom, so that map → odom → base_link is the estimate at the last
  // iteration, with odom → base_link the robot's raw odometry.
  Pose2 mapToOdom() const;

  // Poses for every scan from the full smoother's iteration poses (scans
  // between iterations follow their odometry from the last iteration); with
  // a bounded history, for the kept scans, the smoother anchored at the
  // oldest kept iteration (see history_scans). Runs
  // the batch optimisation on every call; `details` (if given) receives its
  // result, `last_problem` (if given) the problem of its last optimisation
  // (see smoothFull).
  std::vector<StampedPose> smoothedScanPoses(FullSmootherResult* details = nullptr,
                                             LandmarkGraph* last_problem = nullptr) const;
  // The same from the thesis's RTS smoother over the pose alone (§3.4.5.1).
  std::vector<StampedPose> rtsScanPoses() const;
  std::vector<StampedPose> filteredScanPoses() const;
  // ScanRecord::causal for every scan: what a live run publishes.
  std::vector<StampedPose> causalScanPoses() const;

  // The back end's key scans as the last scan saw them (loop-closed, map frame),
  // with their readings in the robot frame: for a live occupancy grid and
  // the loop-closed path. Empty without loop closure.
  struct KeyScan {
    double stamp = 0.0;
    Pose2 pose;
    std::vector<Vector2> points;
  };
  std::vector<KeyScan> keyScans(bool with_points) const;
  // Optimisations the back end has run: a change means new key-scan poses.
  long backEndOptimisations() const { return view_ ? view_->counters.optimisations : 0; }
  // The back end's counters as the last scan saw them (zero without loop closure).
  LoopClosureCounters backEndCounters() const {
    return view_ ? view_->counters : LoopClosureCounters();
  }
  // Scans handed to the back end that it has not processed yet (its own
  // thread only; inline it is always 0).
  long backEndBacklog() const { return back_end_ ? back_end_->backlog() : 0; }

  // Loop closure (options.loop_closure.enabled): finishLoopClosure() runs
  // the final optimisation after the last scan; optimizedScanPoses() then
  // gives one pose per scan (empty when loop closure is off).
  void finishLoopClosure();
  std::vector<StampedPose> optimizedScanPoses() const;
  // The loop closer itself, once it has processed every scan (waits for
  // the back end's thread); null without loop closure.
  const LoopCloser* loopCloser() const { return back_end_ ? &back_end_->drained() : nullptr; }

 private:
  // One input: a scan (features extracted here) or features extracted
  // elsewhere; exactly one of the two is non-null.
  ScanResult process(double stamp, const Scan* scan, const FeatureSet* features,
                     const Pose2& raw_odometry);
  void iterate(double stamp, const Scan* scan, const FeatureSet* features, const Pose2& odometry,
               bool predict, double dt, ScanResult* out);
  Pose2 deadReckoned(const Pose2& odometry) const;
  Matrix3 deadReckonedCovariance(const Pose2& odometry) const;
  int pruneRarelySeen();  // returns how many landmarks were removed
  int boundLandmarks();   // max_landmarks; returns how many were marginalised
  // points+mecp: the MECP of the scan's matched point landmarks as an extra
  // update (ekf_slam_core/mecp/mecp_update.h), counted.
  void updateMecp(const ScanResult& result);
  void trackKeyScans();
  // rooms.enabled: the rooms from the walls mapped now; every point landmark relabelled.
  void rebuildRooms();
  void reanchorFilter(const Pose2& causal, const Pose2& published);
  void trimHistory();  // options_.history_scans
  std::vector<StampedPose> scanPosesFrom(const std::vector<Pose2>& iteration_poses) const;
  std::vector<IterationConstraint> loopConstraints() const;
  std::vector<Pose2> loopClosedIterationPoses() const;  // empty without loop closure

  PipelineOptions options_;
  std::unique_ptr<ScanMatchingOdometry> scan_matcher_;  // null when disabled
  // The full smoother's motion edges (FullSmootherOptions::motion_edges):
  // null unless they come from a local matcher beside a global front end.
  std::unique_ptr<ScanMatchingOdometry> local_matcher_;
  Pose2 local_pose_;       // the local matcher's pose at the scan being processed
  Pose2 last_local_pose_;  // … and at the last iteration (or re-anchor)
  std::unique_ptr<LoopClosureBackEnd> back_end_;  // null when loop closure is off
  std::unique_ptr<LineLandmarks> lines_;          // null with points only
  std::unique_ptr<RoomGate> room_gate_;           // rooms.enabled, once a rebuild found rooms
  long iterations_since_rooms_ = 0;
  // rooms.enabled: per point landmark id, where the laser was when it was created
  std::unordered_map<int, Vector2> landmark_seen_from_;
  std::shared_ptr<const BackEndView> view_;  // the back end as the last scan saw it
  long loops_seen_ = 0;                      // accepted loops in that view
  EkfSlam filter_;
  TrajectoryRecorder recorder_;
  FullSmootherRecorder full_recorder_;
  // Record number of each scan given to the loop closer (from loop scan
  // first_loop_scan_ on; both count from the run's first).
  std::vector<int> record_of_loop_scan_;
  int first_loop_scan_ = 0;
  std::vector<Pose2> key_filtered_;     // the filter's pose at each key scan (map frame)
  std::deque<Pose2> pending_filtered_;  // the filter's pose at loop scans pending_base_ …
  long pending_base_ = 0;               // … on, whose key scans the back end may still report
  std::unordered_map<int, int> landmark_scan_;  // landmark id → loop scan that created it
  bool have_map_from_graph_ = false;  // map_from_graph_ is set (at the first recorded scan)
  Pose2 map_from_graph_;              // the loop closer's frame in the map frame
  PipelineCounters counters_;
  std::vector<ScanRecord> records_;  // scans first_record_ on
  long first_record_ = 0;
  int first_iteration_ = 0;  // iteration number of recorder_'s and full_recorder_'s first
  bool initialised_ = false;
  Pose2 last_odometry_;         // control-source pose at the last iteration (or re-anchor)
  Pose2 last_raw_odometry_;     // the robot's raw odometry at that iteration
  Pose2 current_raw_odometry_;  // the raw odometry of the scan being processed
  double last_stamp_ = 0.0;
  Pose2 latest_odometry_;            // odometry at the latest scan
  bool accept_next_motion_ = false;  // acceptNextMotion(): no jump rule at the next iteration
};

}  // namespace ekf_slam
