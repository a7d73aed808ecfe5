// p3dx_emulator: a Pioneer P3-DX on a pseudo-terminal, for the driver to
// connect to as if it were the robot.
//
//   rosrun ekf_slam p3dx_emulator --link /tmp/p3dx [options]
//
// Works without a roscore. With --ros it also publishes its true pose
// (~ground_truth) and its own encoder odometry (~odometry) as
// nav_msgs/Odometry and offers ~set_connected / ~set_stalled
// (std_srvs/SetBool) for tests. --pose-log FILE writes the same as text.
// Options: see usage() below and docs/p3dx_driver.md.
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>

#include "p3dx_driver/emulator/p3dx_emulator.h"
#include "ros_conversions/pose_conversion.h"
#include "serial_io/pseudo_terminal.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

void usage() {
  std::cerr << "usage: p3dx_emulator --link PATH [options]\n"
               "  --link PATH           symlink to create for the driver (required)\n"
               "  --name NAME           robot name in the handshake (emulated)\n"
               "  --subclass S          p3dx | p3dx-sh (p3dx)\n"
               "  --baud N              answer only at this baud, 0 = any (9600)\n"
               "  --wheel-noise F       std of wheel distance error, fraction (0)\n"
               "  --seed N              random seed (1)\n"
               "  --corrupt-rate P      fraction of SIPs with a bad checksum (0)\n"
               "  --garbage-rate P      fraction of SIPs preceded by garbage (0)\n"
               "  --drop-rate P         fraction of SIPs missing one byte (0)\n"
               "  --stall               wheels blocked from the start\n"
               "  --stale-session       start streaming as if a client left it open\n"
               "  --disconnect-at T --disconnect-for D   unplug at T s for D s\n"
               "  --pose-log FILE       write t, true pose, odometry pose, v, w per SIP\n"
               "  --ros                 publish ~ground_truth, ~odometry; services\n";
}

bool parseDouble(const char* text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text, &end);
  return end != text && *end == '\0';
}

nav_msgs::Odometry toMessage(const ekf_slam::Pose2& pose, double v, double w, ros::Time stamp,
                             const std::string& frame) {
  nav_msgs::Odometry message;
  message.header.stamp = stamp;
  message.header.frame_id = frame;
  message.child_frame_id = "emulated_base_link";
  message.pose.pose.position.x = pose.x;
  message.pose.pose.position.y = pose.y;
  message.pose.pose.orientation = ekf_slam::ros_conversions::quaternionOfYaw(pose.theta);
  message.twist.twist.linear.x = v;
  message.twist.twist.angular.z = w;
  return message;
}

}  // namespace

int main(int argc, char** argv) {
  bool use_ros = false;
  for (int i = 1; i < argc; ++i) use_ros |= std::strcmp(argv[i], "--ros") == 0;
  if (use_ros) ros::init(argc, argv, "p3dx_emulator", ros::init_options::NoSigintHandler);

  p3dx::EmulatorOptions options;
  std::string link, pose_log;
  double disconnect_at = -1.0, disconnect_for = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--ros") continue;
    if (arg.rfind("__", 0) == 0 || arg.find(":=") != std::string::npos) continue;  // roslaunch
    if (arg == "--stall") {
      options.faults.stalled = true;
      continue;
    }
    if (arg == "--stale-session") {
      options.stale_session = true;
      continue;
    }
    if (arg == "--help" || arg == "-h") {
      usage();
      return 0;
    }
    if (i + 1 >= argc) {
      std::cerr << "p3dx_emulator: option " << arg << " needs a value\n";
      usage();
      return 2;
    }
    const char* value = argv[++i];
    double number = 0.0;
    const bool numeric = parseDouble(value, &number);
    if (arg == "--link") {
      link = value;
    } else if (arg == "--name") {
      options.name = value;
    } else if (arg == "--subclass") {
      options.subclass = value;
    } else if (arg == "--pose-log") {
      pose_log = value;
    } else if (!numeric) {
      std::cerr << "p3dx_emulator: " << arg << " expects a number, got '" << value << "'\n";
      return 2;
    } else if (arg == "--baud") {
      options.baud = static_cast<int>(number);
    } else if (arg == "--wheel-noise") {
      options.wheel_noise = number;
    } else if (arg == "--seed") {
      options.seed = static_cast<uint32_t>(number);
    } else if (arg == "--corrupt-rate") {
      options.faults.corrupt_rate = number;
    } else if (arg == "--garbage-rate") {
      options.faults.garbage_rate = number;
    } else if (arg == "--drop-rate") {
      options.faults.drop_rate = number;
    } else if (arg == "--disconnect-at") {
      disconnect_at = number;
    } else if (arg == "--disconnect-for") {
      disconnect_for = number;
    } else {
      std::cerr << "p3dx_emulator: unknown option " << arg << "\n";
      usage();
      return 2;
    }
  }
  if (link.empty()) {
    std::cerr << "p3dx_emulator: --link PATH is required\n";
    usage();
    return 2;
  }
  if (options.subclass != "p3dx" && options.subclass != "p3dx-sh") {
    std::cerr << "p3dx_emulator: --subclass must be p3dx or p3dx-sh, got '" << options.subclass
              << "'\n";
    return 2;
  }

  serial_io::PseudoTerminal pty;
  if (!pty.open(link)) {
    std::cerr << "p3dx_emulator: " << pty.error() << "\n";
    return 1;
  }
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  std::cout << "p3dx_emulator: " << options.subclass << " '" << options.name << "' on "
            << pty.devicePath() << " -> " << pty.slavePath() << " at " << options.baud << " baud"
            << std::endl;

  p3dx::P3dxEmulator robot(&pty, options);

  std::unique_ptr<ros::NodeHandle> node;
  ros::Publisher truth_publisher, odometry_publisher;
  ros::ServiceServer connected_service, stalled_service;
  bool want_connected = true;
  if (use_ros) {
    node = std::make_unique<ros::NodeHandle>("~");
    truth_publisher = node->advertise<nav_msgs::Odometry>("ground_truth", 10);
    odometry_publisher = node->advertise<nav_msgs::Odometry>("odometry", 10);
    connected_service =
        node->advertiseService<std_srvs::SetBool::Request, std_srvs::SetBool::Response>(
            "set_connected",
            [&](std_srvs::SetBool::Request& request, std_srvs::SetBool::Response& response) {
              want_connected = request.data;
              response.success = true;
              response.message = request.data ? "replugged" : "unplugged";
              return true;
            });
    stalled_service =
        node->advertiseService<std_srvs::SetBool::Request, std_srvs::SetBool::Response>(
            "set_stalled",
            [&](std_srvs::SetBool::Request& request, std_srvs::SetBool::Response& response) {
              robot.faults().stalled = request.data;
              response.success = true;
              return true;
            });
  }
  std::ofstream log;
  if (!pose_log.empty()) {
    log.open(pose_log);
    if (!log) {
      std::cerr << "p3dx_emulator: cannot write " << pose_log << "\n";
      return 1;
    }
    log << "# t true_x true_y true_theta odom_x odom_y odom_theta v w\n";
  }

  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  double next_publish = 0.0, next_log = 0.0;
  while (!g_stop && (!use_ros || ros::ok())) {
    const double now = std::chrono::duration<double>(Clock::now() - start).count();
    bool plugged = want_connected;
    if (disconnect_at >= 0.0 && now >= disconnect_at && now < disconnect_at + disconnect_for) {
      plugged = false;
    }
    if (!plugged && pty.isOpen()) {
      std::cout << "p3dx_emulator: unplugged at t=" << now << " s" << std::endl;
      pty.unplug();
      robot.dropConnection();
    } else if (plugged && !pty.isOpen()) {
      if (pty.replug()) {
        std::cout << "p3dx_emulator: replugged at t=" << now << " s" << std::endl;
      }
    }
    robot.step(now);
    if (use_ros && now >= next_publish) {
      next_publish = now + 0.02;
      const ros::Time stamp = ros::Time::now();
      truth_publisher.publish(toMessage(robot.truePose(), robot.velocity(),
                                        robot.rotationalVelocity(), stamp, "world"));
      odometry_publisher.publish(toMessage(robot.odometryPose(), robot.velocity(),
                                           robot.rotationalVelocity(), stamp, "emulated_odom"));
      ros::spinOnce();
    }
    if (log.is_open() && now >= next_log) {
      next_log = now + 0.1;
      const auto& t = robot.truePose();
      const auto& o = robot.odometryPose();
      log << now << ' ' << t.x << ' ' << t.y << ' ' << t.theta << ' ' << o.x << ' ' << o.y << ' '
          << o.theta << ' ' << robot.velocity() << ' ' << robot.rotationalVelocity() << '\n';
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const auto& stats = robot.stats();
  std::cout << "p3dx_emulator: exiting; SIPs sent " << stats.sips_sent << " (corrupted "
            << stats.sips_corrupted << "), commands " << stats.commands << ", sessions "
            << stats.sessions_opened << ", watchdog trips " << stats.watchdog_trips << std::endl;
  if (use_ros) ros::shutdown();
  return 0;
}
