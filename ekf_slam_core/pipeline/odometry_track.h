// Odometry samples (odom → base_link) indexed by stamp, interpolated at the
// stamps of laser scans. Real logs deliver odometry at other instants than
// the scans (the Intel log has none within 10 µs of any scan) and not always
// in time order, so samples are sorted by stamp once, and a query
// interpolates between the two samples that bracket it.
#pragma once

#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

class OdometryTrack {
 public:
  struct Sample {
    double stamp;
    Pose2 pose;
  };

  // Non-finite samples are dropped (and counted).
  void add(double stamp, const Pose2& pose);
  // Call after the last add() and before any lookup.
  void finalize();

  enum class Lookup {
    kInterpolated,  // between two samples at most max_gap apart
    kNearest,       // the bracketing samples are farther apart (or only one side): nearest used
    kNone,          // no samples
  };
  // Pose at `stamp`: linear in x, y and (wrapped) θ between the bracketing
  // samples. *distance gets the time to the nearest sample (s).
  Lookup poseAt(double stamp, double max_gap, Pose2* pose, double* distance = nullptr) const;

  size_t size() const { return samples_.size(); }
  int dropped() const { return dropped_; }

 private:
  std::vector<Sample> samples_;
  int dropped_ = 0;
};

}  // namespace ekf_slam
