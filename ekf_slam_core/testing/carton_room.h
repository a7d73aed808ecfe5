// Test world: a 10 m × 7 m room with cartons, plenty of corners, as in the
// thesis's artificially modelled environments (§5.1.2–5.1.3), and an
// island of 1 m × 1 m at (3, 1.5) to drive around.
#pragma once

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace testing {

inline sim::PolygonWorld cartonRoom() {
  sim::PolygonWorld world;
  world.addPolygon({{-2, -2}, {8, -2}, {8, 5}, {-2, 5}});
  world.addBox({1.0, -0.9}, 0.6, 0.4);
  world.addBox({4.0, -1.0}, 0.5, 0.5, 0.3);
  world.addBox({6.9, 0.5}, 0.4, 0.8);
  world.addBox({7.0, 3.5}, 0.6, 0.6, -0.4);
  world.addBox({3.0, 4.0}, 0.8, 0.4);
  world.addBox({-1.0, 3.8}, 0.5, 0.5, 0.5);
  world.addBox({-1.0, 1.5}, 0.4, 0.6);
  world.addBox({3.0, 1.5}, 1.0, 1.0);  // an island the robot drives around
  return world;
}

}  // namespace testing
}  // namespace ekf_slam
