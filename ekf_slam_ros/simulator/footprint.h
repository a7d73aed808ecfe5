// Collision of the round robot body with the walls of a GridWorld. Used by
// the simulator's motion hook (the emulated robot stalls instead of driving
// through a wall) and by the test that checks the shipped waypoint loops.
// No ROS.
#pragma once

#include "ekf_slam_core/sim/grid_world.h"

namespace ekf_slam {
namespace sim {

// True when a disc of `radius` (m) centred at `centre` (world frame) touches
// no occupied cell and lies inside the map (outside the image counts as a
// wall: the shipped worlds are closed, and a robot off the map is a bug).
bool footprintFree(const GridWorld& world, const Vector2& centre, double radius);

// Distance (m) from `centre` to the nearest occupied cell (its closest
// point), searched up to `max_distance`; returns max_distance when nothing
// is nearer. For reporting clearances in tests and logs.
double clearance(const GridWorld& world, const Vector2& centre, double max_distance);

}  // namespace sim
}  // namespace ekf_slam
