// Anything a simulated laser can see: a polygon world or an occupancy image.
// The LMS200 emulator and the simulator ray-cast through this interface.
#pragma once

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace sim {

class RayCaster {
 public:
  virtual ~RayCaster() = default;
  // Distance (m) from `origin` along the world-frame direction `angle` (rad)
  // to the first obstacle, or +inf when nothing is hit within `max_range`.
  virtual double castRay(const Vector2& origin, double angle, double max_range) const = 0;
};

}  // namespace sim
}  // namespace ekf_slam
