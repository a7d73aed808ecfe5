// lms200_emulator: an LMS200 on a pseudo-terminal, scanning a fixed room.
//
//   rosrun ekf_slam lms200_emulator --link /tmp/lms200 [options]
//
// Works without a roscore. When a ROS master is reachable (or with --ros) it
// also publishes the ground truth on ~true_scan (sensor_msgs/LaserScan,
// noise-free ranges, stamp = true first-beam time), ~corrupted_scan (scans
// sent with an injected fault) and ~events (std_msgs/String: "unplugged",
// "replugged", "silent", "talking"). Otherwise it logs to stdout.
// Options: see usage() or docs/sick_lms200_driver.md.
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include "serial_io/pseudo_terminal.h"
#include "sick_lms200_driver/emulator/lms200_emulator.h"
#include "sick_lms200_driver/emulator/room.h"
#include "sick_lms200_driver/protocol/session.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

double wallNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

struct CommandLine {
  std::string link;
  sick_lms200::EmulatorOptions emulator;
  double silence_at = -1.0, silence_for = 0.0;  // s after start
  double unplug_at = -1.0, unplug_for = 0.0;    // s after start
  double duration = -1.0;                       // s; < 0: until SIGINT
  int ros = -1;                                 // -1 auto, 0 never, 1 always
};

void usage() {
  std::fprintf(stderr,
               "usage: lms200_emulator --link PATH [--baud 9600] [--angle 180] "
               "[--resolution 1.0] [--units mm|cm] [--noise 0.01]\n"
               "       [--bad-crc-rate P] [--drop-byte-rate P] [--nak-rate P] [--seed N]\n"
               "       [--silence-at S --silence-for S] [--unplug-at S --unplug-for S]\n"
               "       [--duration S] [--ros | --no-ros]\n");
}

bool parse(int argc, char** argv, CommandLine* line, std::string* error) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("__", 0) == 0 || arg.find(":=") != std::string::npos) continue;  // ROS args
    if (arg == "--ros") {
      line->ros = 1;
      continue;
    }
    if (arg == "--no-ros") {
      line->ros = 0;
      continue;
    }
    if (i + 1 >= argc) {
      *error = arg + " needs a value";
      return false;
    }
    const std::string value = argv[++i];
    char* end = nullptr;
    const double number = std::strtod(value.c_str(), &end);
    const bool numeric = end != value.c_str() && *end == '\0';
    auto need_number = [&](double low, double high) {
      if (!numeric || number < low || number > high) {
        *error = arg + ": '" + value + "' must be a number in [" + std::to_string(low) + ", " +
                 std::to_string(high) + "]";
        return false;
      }
      return true;
    };
    if (arg == "--link") {
      line->link = value;
    } else if (arg == "--units") {
      if (value != "mm" && value != "cm") {
        *error = "--units must be mm or cm";
        return false;
      }
      line->emulator.units =
          value == "mm" ? sick_lms200::Units::kMillimetres : sick_lms200::Units::kCentimetres;
    } else if (arg == "--baud") {
      if (!need_number(0, 1e7) || sick_lms200::baudModeByte(static_cast<int>(number)) < 0) {
        *error = "--baud must be 9600, 19200, 38400 or 500000";
        return false;
      }
      line->emulator.initial_baud = static_cast<int>(number);
    } else if (arg == "--angle") {
      if (!need_number(100, 180)) return false;
      line->emulator.angle_deg = static_cast<int>(number);
    } else if (arg == "--resolution") {
      if (!need_number(0.25, 1.0)) return false;
      line->emulator.resolution_centideg = static_cast<int>(number * 100 + 0.5);
    } else if (arg == "--noise") {
      if (!need_number(0.0, 1.0)) return false;
      line->emulator.range_noise_sigma = number;
    } else if (arg == "--bad-crc-rate") {
      if (!need_number(0.0, 1.0)) return false;
      line->emulator.bad_crc_rate = number;
    } else if (arg == "--drop-byte-rate") {
      if (!need_number(0.0, 1.0)) return false;
      line->emulator.drop_byte_rate = number;
    } else if (arg == "--nak-rate") {
      if (!need_number(0.0, 1.0)) return false;
      line->emulator.nak_rate = number;
    } else if (arg == "--seed") {
      if (!need_number(0, 4e9)) return false;
      line->emulator.seed = static_cast<uint32_t>(number);
    } else if (arg == "--silence-at") {
      if (!need_number(0, 1e9)) return false;
      line->silence_at = number;
    } else if (arg == "--silence-for") {
      if (!need_number(0, 1e9)) return false;
      line->silence_for = number;
    } else if (arg == "--unplug-at") {
      if (!need_number(0, 1e9)) return false;
      line->unplug_at = number;
    } else if (arg == "--unplug-for") {
      if (!need_number(0, 1e9)) return false;
      line->unplug_for = number;
    } else if (arg == "--duration") {
      if (!need_number(0, 1e9)) return false;
      line->duration = number;
    } else {
      *error = "unknown option " + arg;
      return false;
    }
  }
  sick_lms200::SessionOptions variant;
  variant.angle_deg = line->emulator.angle_deg;
  variant.resolution_centideg = line->emulator.resolution_centideg;
  const std::string invalid = sick_lms200::validateSessionOptions(variant);
  if (!invalid.empty()) {
    *error = invalid;
    return false;
  }
  if (line->link.empty()) {
    *error = "--link PATH is required (the symlink the driver opens, e.g. /tmp/lms200)";
    return false;
  }
  return true;
}

sensor_msgs::LaserScan toMessage(const sick_lms200::TrueScan& truth) {
  sensor_msgs::LaserScan msg;
  msg.header.stamp = ros::Time(truth.first_beam_time);
  msg.header.frame_id = "laser";
  // A partial scan's beams are 1° apart from its offset on; a complete
  // scan's at the resolution across the whole angle.
  const double first = -truth.angle_deg / 2.0 + truth.partial_offset_centideg / 100.0;
  const double increment = truth.partial ? 1.0 : truth.resolution_centideg / 100.0;
  const double count = static_cast<double>(truth.ranges.size());
  msg.angle_min = static_cast<float>(ekf_slam::degToRad(first));
  msg.angle_max = static_cast<float>(ekf_slam::degToRad(first + (count - 1) * increment));
  msg.angle_increment = static_cast<float>(ekf_slam::degToRad(increment));
  msg.range_max = 81.82f;
  msg.ranges.assign(truth.ranges.begin(), truth.ranges.end());
  return msg;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine line;
  std::string error;
  if (!parse(argc, argv, &line, &error)) {
    std::fprintf(stderr, "lms200_emulator: %s\n", error.c_str());
    usage();
    return 2;
  }
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);

  std::unique_ptr<ros::NodeHandle> node;
  ros::Publisher truth_pub, corrupted_pub, events_pub;
  if (line.ros != 0) {
    ros::init(argc, argv, "lms200_emulator", ros::init_options::NoSigintHandler);
    if (line.ros == 1 || ros::master::check()) {
      node = std::make_unique<ros::NodeHandle>("~");
      truth_pub = node->advertise<sensor_msgs::LaserScan>("true_scan", 20);
      corrupted_pub = node->advertise<sensor_msgs::LaserScan>("corrupted_scan", 20);
      events_pub = node->advertise<std_msgs::String>("events", 10, true);
    }
  }
  auto event = [&](const std::string& text) {
    std::printf("lms200_emulator: %s\n", text.c_str());
    std::fflush(stdout);
    if (node) {
      std_msgs::String msg;
      msg.data = text;
      events_pub.publish(msg);
    }
  };

  serial_io::PseudoTerminal pty;
  if (!pty.open(line.link)) {
    std::fprintf(stderr, "lms200_emulator: %s\n", pty.error().c_str());
    return 1;
  }
  const ekf_slam::sim::PolygonWorld world = sick_lms200::makeDemoRoom();
  sick_lms200::Lms200Emulator emulator(
      pty, world, [](double) { return sick_lms200::demoSensorPose(); }, line.emulator);
  emulator.setPeerBaudSource([&pty] { return pty.peerBaud(); });
  uint64_t scans = 0;
  emulator.setScanObserver([&](const sick_lms200::TrueScan& truth) {
    scans++;
    if (!node) return;
    (truth.corrupted ? corrupted_pub : truth_pub).publish(toMessage(truth));
  });
  event("ready on " + line.link + " -> " + pty.slavePath() + " at " +
        std::to_string(emulator.baud()) + " baud");

  const double start = wallNow();
  bool unplugged = false, unplug_done = false, silent = false, silence_done = false;
  int last_baud = emulator.baud();
  while (!g_stop && (!node || ros::ok())) {
    const double now = wallNow();
    const double elapsed = now - start;
    if (line.duration >= 0 && elapsed > line.duration) break;
    if (!unplug_done && line.unplug_at >= 0 && elapsed >= line.unplug_at && !unplugged) {
      pty.unplug();
      unplugged = true;
      event("unplugged");
    }
    if (unplugged && elapsed >= line.unplug_at + line.unplug_for) {
      if (!pty.replug()) {
        std::fprintf(stderr, "lms200_emulator: replug failed: %s\n", pty.error().c_str());
        return 1;
      }
      unplugged = false;
      unplug_done = true;
      event("replugged");
    }
    if (!silence_done && line.silence_at >= 0 && elapsed >= line.silence_at && !silent) {
      emulator.setSilent(true);
      silent = true;
      event("silent");
    }
    if (silent && elapsed >= line.silence_at + line.silence_for) {
      emulator.setSilent(false);
      silent = false;
      silence_done = true;
      event("talking");
    }
    if (!unplugged) emulator.spinOnce(now);
    if (emulator.baud() != last_baud) {
      last_baud = emulator.baud();
      event("baud " + std::to_string(last_baud));
    }
    // Sleep until the next byte is due (the end of a telegram exactly), at
    // most 5 ms so that requests are answered promptly.
    const double wake = std::min(emulator.nextDeadline(now), wallNow() + 0.005);
    const double sleep = wake - wallNow();
    if (sleep > 0) std::this_thread::sleep_for(std::chrono::duration<double>(sleep));
  }
  event("stopping after " + std::to_string(scans) + " scans");
  pty.close();
  if (node) ros::shutdown();
  return 0;
}
