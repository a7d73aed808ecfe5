// p3dx_driver_node: drives a Pioneer P3-DX over its serial port.
//   rosrun ekf_slam p3dx_driver_node _port:=/dev/ttyUSB0
// Parameters, topics and services: docs/p3dx_driver.md.
#include <ros/ros.h>

#include "p3dx_driver/node/driver_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "p3dx_driver");
  ros::NodeHandle node;
  ros::NodeHandle private_node("~");
  p3dx::DriverParams params;
  std::string error;
  if (!p3dx::loadDriverParams(private_node, &params, &error)) {
    ROS_FATAL("p3dx: %s", error.c_str());
    return 1;
  }
  p3dx::DriverNode driver(node, private_node, params);
  driver.run();
  return 0;
}
