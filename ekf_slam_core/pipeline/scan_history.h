// The pipeline's one bounded history: a record per scan (the pose it was
// given, its odometry and the iteration it hangs off) and the filter's
// iterations as the smoothers need them. The trajectory files, the
// smoothers (~smooth, the offline runner) and the back end's loop
// constraints read it; the causal estimate never does, so the poses a scan
// is given do not depend on the bound.
//
// Bound (PipelineOptions::history_scans): 0 keeps every scan; n > 0 keeps
// at least the newest n scans (trimmed in steps of n / 8, so at most 9n/8)
// with the iterations they hang off. The oldest kept iteration then takes
// the place of the first pose for the full smoother: its prior is the
// filter's pose and covariance at that iteration.
//
// Readings (PipelineOptions::keep_readings, a live node's choice): each
// recorded scan's readings are kept beside its record, for a grid cast
// along smoothed poses. With a bound n the readings of the newest n scans
// are kept; an older scan's leave one at a time, each cast into the
// history's own occupancy grid at the scan's causal pose as it goes. One
// scan leaves per scan (not n/8 with each trim of the records): a trim's
// worth of ray casts at once would stall the scan that triggers it.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_core/smoother/full_smoother.h"
#include "ekf_slam_core/smoother/rts_smoother.h"

namespace ekf_slam {

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

// A recorded scan's readings as the laser gave them. The ranges are kept as
// float32, as a laser driver sends them: half the memory of the core's
// doubles, and the same values when converted back.
struct KeptScan {
  long scan = 0;  // its record's number (counting from the run's first scan)
  std::vector<float> ranges;
  double angle_min = 0.0, angle_increment = 0.0, range_min = 0.0, range_max = 0.0, stamp = 0.0;
  Pose2 causal;  // ScanRecord::causal of it: where a grid of the left scans casts it
  KeptScan(long scan, const Scan& readings, const Pose2& causal);
  Scan toScan() const;
};

// Which readings the history keeps (PipelineOptions::keep_readings).
struct KeptReadingsOptions {
  bool keep = false;
  OccupancyGridOptions grid;  // of the scans that left the kept readings
  Pose2 laser_pose;           // base_link → laser, where the rays start
};

// What a ScanHistory holds apart from the kept readings: a saved state
// carries it (slam_state.h), so that a resumed run's smoothers and
// trajectories go on over the saved scans as if the run had not stopped.
struct ScanHistoryState {
  std::vector<ScanRecord> records;  // scans first_record on
  long first_record = 0;
  int first_iteration = 0;
  std::vector<SmootherStep> steps;                      // the RTS smoother's, one per iteration
  std::vector<SmootherIteration> iterations;            // the full smoother's, one per iteration
  std::vector<std::pair<int, int>> merged_into;         // dropped landmark id → kept id, by id
  std::vector<std::pair<int, Vector2>> last_estimates;  // landmark id → estimate, by id
  Pose2 prior_mean;                                     // of the first iteration
  Matrix3 prior_covariance = Matrix3::Zero();
};

// Keeps the newest `max_scans` records of `state` (0: all) and the
// iterations they hang off; the oldest kept iteration becomes the first,
// with the filter's estimate there as its prior (as a bounded history
// trims itself).
void keepNewestScans(long max_scans, ScanHistoryState* state);

class ScanHistory {
 public:
  // `bound`: history_scans. The full smoother's first pose is `prior`.
  ScanHistory(long bound, const Pose2& prior, const Matrix3& prior_covariance,
              const KeptReadingsOptions& readings = {});

  // What it holds, and the way back: restore() replaces the records and
  // iterations (the kept readings and their grid are cleared; the bound
  // stays this history's own). Empty on success, else what does not fit
  // together in `state` (the history is then unchanged).
  ScanHistoryState state() const;
  std::string restore(const ScanHistoryState& state);

  // The prediction of an iteration (for the RTS smoother) …
  void addTransition(const Matrix3& F, const Pose2& predicted, const Matrix3& predicted_cov) {
    recorder_.addTransition(F, predicted, predicted_cov);
  }
  // … and the iteration itself, after its updates (see
  // FullSmootherRecorder::addIteration).
  void addIteration(double stamp, const EkfSlam& filter, const OdometryControl* control,
                    const std::vector<PointObservation>& observations,
                    const IterationReport& report, const Pose2* local_motion, const Pose2* wheels);
  // Number of the newest iteration (counting from the run's first; −1
  // before the first).
  int currentIteration() const {
    return first_iteration_ + static_cast<int>(recorder_.steps().size()) - 1;
  }
  // Appends a scan's record (and, when readings are kept, the readings of
  // `scan` if given), then trims to the bound. Returns the number of
  // records dropped from the front (0 almost always).
  long add(const ScanRecord& record, const Scan* scan = nullptr);

  // Records of scans firstScan() to recordedScans() − 1, and the
  // iterations from firstIteration() on.
  const std::vector<ScanRecord>& records() const { return records_; }
  long firstScan() const { return first_record_; }
  long recordedScans() const { return first_record_ + static_cast<long>(records_.size()); }
  // The record of scan `scan` (counting from the run's first), or null when
  // it is not kept.
  const ScanRecord* record(long scan) const;
  int firstIteration() const { return first_iteration_; }
  const TrajectoryRecorder& iterations() const { return recorder_; }
  const FullSmootherRecorder& smootherRecord() const { return full_recorder_; }

  // The kept readings, oldest first (empty unless readings are kept).
  const std::deque<KeptScan>& keptScans() const { return kept_; }
  // The readings of scan `scan`, or null when they are not kept.
  const KeptScan* keptScan(long scan) const;
  // The grid of the scans whose readings left; null while none has.
  const OccupancyGrid* leftScansGrid() const { return left_grid_ ? &*left_grid_ : nullptr; }

  // One pose per kept scan from one pose per kept iteration (scans between
  // iterations follow their odometry from their iteration); a scan whose
  // iteration has no pose keeps its filtered one.
  std::vector<StampedPose> scanPosesFrom(const std::vector<Pose2>& iteration_poses) const;
  std::vector<StampedPose> filteredScanPoses() const;
  std::vector<StampedPose> causalScanPoses() const;
  // The thesis's RTS smoother over the pose alone (§3.4.5.1).
  std::vector<StampedPose> rtsScanPoses() const;

 private:
  long bound_;
  std::vector<ScanRecord> records_;  // scans first_record_ on
  long first_record_ = 0;
  int first_iteration_ = 0;  // iteration number of recorder_'s and full_recorder_'s first
  TrajectoryRecorder recorder_;
  FullSmootherRecorder full_recorder_;
  KeptReadingsOptions readings_;
  std::deque<KeptScan> kept_;               // the newest `bound_` scans' readings
  std::optional<OccupancyGrid> left_grid_;  // the scans that left kept_
};

}  // namespace ekf_slam
