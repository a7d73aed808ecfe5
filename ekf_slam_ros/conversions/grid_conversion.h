// nav_msgs/OccupancyGrid ↔ the map_server file form of the core
// (ekf_slam_core/io/grid_map_file.h): ~save_map and ~load_map.
#pragma once

#include <nav_msgs/OccupancyGrid.h>

#include "ekf_slam_core/io/grid_map_file.h"

namespace ekf_slam {
namespace ros_conversions {

GridMapFile toGridMapFile(const nav_msgs::OccupancyGrid& map);
// header: the frame and stamp to publish with (also map_load_time).
nav_msgs::OccupancyGrid toOccupancyGridMessage(const GridMapFile& grid,
                                               const std_msgs::Header& header);

}  // namespace ros_conversions
}  // namespace ekf_slam
