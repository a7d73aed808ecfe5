#include "ekf_slam_core/pipeline/smoothing_problem.h"

#include <utility>

namespace ekf_slam {

std::vector<StampedPose> SmoothingProblem::solve(FullSmootherResult* details,
                                                 LandmarkGraph* last_problem) const {
  return solveSmoothing(history, filter, loops, initial, options, details, last_problem);
}

std::vector<StampedPose> solveSmoothing(const ScanHistory& history, const EkfSlam& filter,
                                        const std::vector<IterationConstraint>& loops,
                                        const std::vector<Pose2>& initial,
                                        const FullSmootherOptions& options,
                                        FullSmootherResult* details, LandmarkGraph* last_problem) {
  if (options.method == SmootherMethod::kRts) {
    if (details) *details = FullSmootherResult();
    return history.rtsScanPoses();
  }
  const FullSmootherRecorder& record = history.smootherRecord();
  FullSmootherResult result;
  if (history.firstIteration() > 0 && !initial.empty()) {
    // A bounded history starts at its oldest iteration: anchored where the
    // loop-closed graph has it (the frame of the older key scans), as
    // uncertain as the filter was there.
    FullSmootherRecorder window = record;
    window.setPrior(initial.front(), record.priorCovariance());
    result = smoothFull(window, filter, loops, options, &initial, last_problem);
  } else {
    result = smoothFull(record, filter, loops, options, initial.empty() ? nullptr : &initial,
                        last_problem);
  }
  std::vector<StampedPose> out = history.scanPosesFrom(result.poses);
  if (details) *details = std::move(result);
  return out;
}

}  // namespace ekf_slam
