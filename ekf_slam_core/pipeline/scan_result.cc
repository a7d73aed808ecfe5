#include "ekf_slam_core/pipeline/scan_result.h"

namespace ekf_slam {

const char* toString(ScanOutcome outcome) {
  switch (outcome) {
    case ScanOutcome::kIterated:
      return "iterated";
    case ScanOutcome::kSkippedNoMotion:
      return "skipped (no motion)";
    case ScanOutcome::kSkippedTimeNotIncreasing:
      return "skipped (time not increasing)";
    case ScanOutcome::kRejectedOdometryJump:
      return "rejected (odometry jump)";
    case ScanOutcome::kRejectedBadInput:
      return "rejected (bad input)";
  }
  return "unknown";
}

}  // namespace ekf_slam
