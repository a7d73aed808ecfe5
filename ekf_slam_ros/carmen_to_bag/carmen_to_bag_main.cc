// carmen_to_bag: converts a CARMEN text log into a ROS bag (see carmen_to_bag.h).
//
//   rosrun ekf_slam carmen_to_bag LOG BAG
//
// Exit code 0 on success, 1 on bad arguments, 2 when the log cannot be read
// or the bag cannot be written (the message names the file and line).
#include <iostream>

#include "ekf_slam_ros/carmen_to_bag/carmen_to_bag.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: carmen_to_bag LOG BAG\n";
    return 1;
  }
  ekf_slam::CarmenToBagSummary summary;
  const std::string error = ekf_slam::convertCarmenToBag(argv[1], argv[2], &summary);
  if (!error.empty()) {
    std::cerr << "carmen_to_bag: " << error << "\n";
    return 2;
  }
  std::cout << "carmen_to_bag: " << summary.scans << " scans written to " << argv[2] << " ("
            << summary.skipped_lines << " lines of other message types skipped)\n";
  return 0;
}
