// What the node's parts (services, grids, diagnostics) may see and ask of
// the SLAM state that SlamNode owns: the pipeline (null before the first
// scan) and the few operations that restart it. SlamNode implements it;
// the parts are given it at construction, so none of them reaches into
// SlamNode's members.
#pragma once

#include <ros/time.h>

#include <optional>
#include <string>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"

namespace ekf_slam {

class SlamControl {
 public:
  virtual ~SlamControl() = default;

  // Null before the first scan (the laser pose is not known yet) and
  // after a reset until the next scan.
  virtual const SlamPipeline* pipeline() const = 0;
  // The next iteration takes the odometry increment as a move that was
  // made (the robot was driven while paused); nothing without a pipeline.
  virtual void acceptNextMotion() = 0;
  virtual ros::Time lastScanStamp() const = 0;
  // Changes whenever the map restarts (~reset, a loaded map, an initial
  // pose): a result computed from an older state is not published.
  virtual long generation() const = 0;
  virtual bool localizeOnly() const = 0;
  // The pipeline's landmarks, else the loaded map waiting for it, else none.
  virtual std::optional<LandmarkMapFile> landmarks() const = 0;
  // Empties the queue of inputs waiting for their transforms.
  virtual void dropWaitingInputs() = 0;
  // ~reset: an empty map, the parameters' localize_only; the next scan
  // starts a new one.
  virtual void clearMap() = 0;
  // The filter restarts at `pose` (map frame) with `covariance`, `prior`
  // as its landmarks (uncorrelated with the pose): at once when the laser
  // pose is known, else at the next scan. Empty when done, else why the
  // pose is unusable (nothing changed).
  virtual std::string restart(const Pose2& pose, const Matrix3& covariance,
                              std::optional<LandmarkMapFile> prior, bool localize_only) = 0;
  // ~write_state: everything a later run goes on from; none before the
  // first scan. Waits for the loop closer to process the scans handed to it.
  virtual std::optional<SlamState> state() const = 0;
  // ~load_state: the map, key scans and graph of `state` replace the
  // running ones, at once when the laser pose is known (else at the next
  // scan), mapping on from there or (localize_only) localising in it.
  // Empty when done, else why it was refused (nothing changed).
  virtual std::string resumeFrom(SlamState state, bool localize_only) = 0;
};

}  // namespace ekf_slam
