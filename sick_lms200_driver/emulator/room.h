// The fixed world of the stand-alone emulator: a 10 m × 6 m room with two
// cartons and a pillar, and the sensor's pose in it. The walls lie beyond
// the 8.18 m mm-mode range in some directions, so scans contain "no return"
// codes too.
#pragma once

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sim/polygon_world.h"

namespace sick_lms200 {

inline ekf_slam::sim::PolygonWorld makeDemoRoom() {
  using ekf_slam::Vector2;
  ekf_slam::sim::PolygonWorld world;
  world.addPolygon({Vector2(0.0, 0.0), Vector2(10.0, 0.0), Vector2(10.0, 6.0), Vector2(0.0, 6.0)});
  world.addBox(Vector2(4.0, 1.5), 0.6, 0.4, 0.3);
  world.addBox(Vector2(6.5, 4.2), 0.5, 0.5, -0.5);
  world.addBox(Vector2(3.0, 4.5), 0.2, 0.2);
  return world;
}

// Sensor pose in the room: near the left wall, looking along the room.
inline ekf_slam::Pose2 demoSensorPose() { return ekf_slam::Pose2(1.0, 3.0, 0.05); }

}  // namespace sick_lms200
