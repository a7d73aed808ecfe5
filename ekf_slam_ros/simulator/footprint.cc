#include "ekf_slam_ros/simulator/footprint.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {
namespace sim {

double clearance(const GridWorld& world, const Vector2& centre, double max_distance) {
  const double resolution = world.resolution();
  const Vector2 origin = world.origin();
  const int x_low =
      static_cast<int>(std::floor((centre.x() - max_distance - origin.x()) / resolution));
  const int x_high =
      static_cast<int>(std::floor((centre.x() + max_distance - origin.x()) / resolution));
  const int y_low =
      static_cast<int>(std::floor((centre.y() - max_distance - origin.y()) / resolution));
  const int y_high =
      static_cast<int>(std::floor((centre.y() + max_distance - origin.y()) / resolution));
  double nearest = max_distance;
  for (int iy = y_low; iy <= y_high; ++iy) {
    for (int ix = x_low; ix <= x_high; ++ix) {
      const bool outside = ix < 0 || iy < 0 || ix >= world.width() || iy >= world.height();
      if (!outside && !world.occupied(ix, iy)) continue;
      // Closest point of the cell's square to the centre.
      const double cell_x = origin.x() + ix * resolution;
      const double cell_y = origin.y() + iy * resolution;
      const double dx = centre.x() - std::clamp(centre.x(), cell_x, cell_x + resolution);
      const double dy = centre.y() - std::clamp(centre.y(), cell_y, cell_y + resolution);
      nearest = std::min(nearest, std::hypot(dx, dy));
    }
  }
  return nearest;
}

bool footprintFree(const GridWorld& world, const Vector2& centre, double radius) {
  // A tiny extra search distance so that "touching" (distance == radius)
  // is found and counted as a collision.
  return clearance(world, centre, radius + 1e-9) > radius;
}

}  // namespace sim
}  // namespace ekf_slam
