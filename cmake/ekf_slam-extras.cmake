# Read by find_package(ekf_slam) (catkin_package CFG_EXTRAS), in the
# development and the install space alike. The core's libraries are static,
# so what they link reaches their users' link lines: the threads of the back
# end, Eigen, whose headers the core's headers include, and yaml-cpp, which
# reads and writes the map files (ekf_slam_io). They follow the core's
# libraries in ekf_slam_LIBRARIES, which lists those users first.
find_package(Eigen3 REQUIRED NO_MODULE)
find_package(Threads REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(EKF_SLAM_YAML_CPP REQUIRED IMPORTED_TARGET yaml-cpp)
list(APPEND ekf_slam_INCLUDE_DIRS ${EIGEN3_INCLUDE_DIRS})
list(APPEND ekf_slam_LIBRARIES Threads::Threads Eigen3::Eigen PkgConfig::EKF_SLAM_YAML_CPP)
