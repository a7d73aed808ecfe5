// The pipeline's configuration: every option of every stage (front end,
// filter and its landmark strategies, back end, smoother), with the
// bounds each number must respect. One PipelineOptions serves the live
// node, the offline runner and the tests; its fields are the sections of
// config/ekf_slam.yaml.
#pragma once

#include <string>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/filter/data_association.h"
#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/loop_closure/loop_closer.h"
#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_core/mecp/room_gating.h"
#include "ekf_slam_core/pipeline/line_landmarks.h"
#include "ekf_slam_core/scan_matching/scan_matcher.h"
#include "ekf_slam_core/smoother/full_smoother.h"

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
  // Keep each recorded scan's readings in the history, for a grid cast
  // along smoothed poses (the live node's ~smooth without loop closure):
  // float32 ranges and their geometry (ScanHistory::keptScans). With
  // history_scans n > 0 the readings of the newest n scans are kept, and
  // an older scan's are cast into the history's own occupancy grid
  // (readings_grid; ScanHistory::leftScansGrid) at its causal pose as it
  // leaves, so that the grid still covers every place the robot saw in
  // memory that grows with the area, not the time. The poses do not depend
  // on it. Not a file setting: the program decides (the offline runner
  // keeps no readings).
  bool keep_readings = false;
  OccupancyGridOptions readings_grid;
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

}  // namespace ekf_slam
