#include "ekf_slam_ros/conversions/grid_conversion.h"

#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace ros_conversions {

GridMapFile toGridMapFile(const nav_msgs::OccupancyGrid& map) {
  GridMapFile grid;
  grid.resolution = map.info.resolution;
  grid.width = static_cast<int>(map.info.width);
  grid.height = static_cast<int>(map.info.height);
  grid.origin_x = map.info.origin.position.x;
  grid.origin_y = map.info.origin.position.y;
  grid.origin_yaw = yawOf(map.info.origin.orientation);
  grid.cells = map.data;
  return grid;
}

nav_msgs::OccupancyGrid toOccupancyGridMessage(const GridMapFile& grid,
                                               const std_msgs::Header& header) {
  nav_msgs::OccupancyGrid map;
  map.header = header;
  map.info.map_load_time = header.stamp;
  map.info.resolution = static_cast<float>(grid.resolution);
  map.info.width = static_cast<uint32_t>(grid.width);
  map.info.height = static_cast<uint32_t>(grid.height);
  map.info.origin.position.x = grid.origin_x;
  map.info.origin.position.y = grid.origin_y;
  map.info.origin.orientation = quaternionOfYaw(grid.origin_yaw);
  map.data = grid.cells;
  return map;
}

}  // namespace ros_conversions
}  // namespace ekf_slam
