#include "ekf_slam_ros/simulator/ground_truth.h"

#include <cmath>

namespace ekf_slam {
namespace sim {

geometry_msgs::Pose toPoseMessage(const Pose2& pose) {
  geometry_msgs::Pose message;
  message.position.x = pose.x;
  message.position.y = pose.y;
  message.orientation.z = std::sin(pose.theta / 2.0);
  message.orientation.w = std::cos(pose.theta / 2.0);
  return message;
}

nav_msgs::Odometry toOdometry(const Pose2& pose, double velocity, double rotational_velocity,
                              const ros::Time& stamp, const std::string& frame,
                              const std::string& child_frame) {
  nav_msgs::Odometry message;
  message.header.stamp = stamp;
  message.header.frame_id = frame;
  message.child_frame_id = child_frame;
  message.pose.pose = toPoseMessage(pose);
  // Exact by construction: zero covariance is the truth here, not "unknown".
  message.twist.twist.linear.x = velocity;
  message.twist.twist.angular.z = rotational_velocity;
  return message;
}

nav_msgs::OccupancyGrid toOccupancyGrid(const GridWorld& world, const Pose2& frame_in_world,
                                        const ros::Time& stamp, const std::string& frame) {
  nav_msgs::OccupancyGrid grid;
  grid.header.stamp = stamp;
  grid.header.frame_id = frame;
  grid.info.map_load_time = stamp;
  grid.info.resolution = static_cast<float>(world.resolution());
  grid.info.width = static_cast<uint32_t>(world.width());
  grid.info.height = static_cast<uint32_t>(world.height());
  // Cell (0, 0)'s corner, in the world, then seen from the target frame.
  const Pose2 origin_in_world(world.origin().x(), world.origin().y(), 0.0);
  grid.info.origin = toPoseMessage(between(frame_in_world, origin_in_world));
  grid.data.resize(static_cast<size_t>(world.width()) * world.height());
  for (int iy = 0; iy < world.height(); ++iy) {
    for (int ix = 0; ix < world.width(); ++ix) {
      grid.data[static_cast<size_t>(iy) * world.width() + ix] = world.occupied(ix, iy) ? 100 : 0;
    }
  }
  return grid;
}

}  // namespace sim
}  // namespace ekf_slam
