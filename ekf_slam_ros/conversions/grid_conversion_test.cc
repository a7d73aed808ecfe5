#include "ekf_slam_ros/conversions/grid_conversion.h"

#include <gtest/gtest.h>

namespace ekf_slam {
namespace ros_conversions {
namespace {

TEST(GridConversion, AMessageRoundTripsThroughTheFileForm) {
  nav_msgs::OccupancyGrid map;
  map.info.resolution = 0.05f;
  map.info.width = 4;
  map.info.height = 3;
  map.info.origin.position.x = -1.25;
  map.info.origin.position.y = 2.5;
  map.info.origin.orientation.w = 1.0;
  map.data = {-1, 0, 100, 0, 100, -1, -1, 0, 0, 100, 100, 0};
  std_msgs::Header header;
  header.frame_id = "map";
  header.stamp = ros::Time(12.5);
  const nav_msgs::OccupancyGrid back = toOccupancyGridMessage(toGridMapFile(map), header);
  EXPECT_EQ(back.info.resolution, map.info.resolution);
  EXPECT_EQ(back.info.width, map.info.width);
  EXPECT_EQ(back.info.height, map.info.height);
  EXPECT_EQ(back.info.origin.position.x, map.info.origin.position.x);
  EXPECT_EQ(back.info.origin.position.y, map.info.origin.position.y);
  EXPECT_EQ(back.info.origin.orientation.w, 1.0);
  EXPECT_EQ(back.info.origin.orientation.z, 0.0);
  EXPECT_EQ(back.data, map.data);
  EXPECT_EQ(back.header.frame_id, "map");
  EXPECT_EQ(back.info.map_load_time, header.stamp);
}

}  // namespace
}  // namespace ros_conversions
}  // namespace ekf_slam
