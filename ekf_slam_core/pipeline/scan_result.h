// What the pipeline gives for one scan: how it was used (ScanOutcome), the
// pose and covariance it was given, and what the filter made of it.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/pipeline/line_landmarks.h"

namespace ekf_slam {

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

}  // namespace ekf_slam
