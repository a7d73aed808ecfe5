// lms200_node: the ROS face of ScannerLink. Publishes sensor_msgs/LaserScan
// on `scan` and a "LMS200" status on /diagnostics; all protocol work, the
// reconnect logic and the stamp estimate live in the ROS-free library.
// Parameters, topics and frames: docs/sick_lms200_driver.md.
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <thread>

#include "ros_params/private_params.h"
#include "sick_lms200_driver/node/laser_scan_conversion.h"
#include "sick_lms200_driver/protocol/scanner_link.h"

namespace {

using sick_lms200::LinkOptions;

using sick_lms200::LinkStats;

struct NodeOptions {
  LinkOptions link;
  sick_lms200::ScanMessageOptions message;
};

// Reads the private parameters; false (with a message naming the key) when
// one is unknown, of the wrong type or out of range.
bool loadOptions(const ros::NodeHandle& pnh, NodeOptions* options, std::string* error) {
  ekf_slam::PrivateParams read(pnh);
  LinkOptions& link = options->link;
  read.text("port", &link.port);
  read.integer("baud", &link.session.baud, 1200, 500000);
  read.integer("angle", &link.session.angle_deg, 100, 180);
  double resolution = link.session.resolution_centideg / 100.0;
  read.number("resolution", &resolution, 0.25, 1.0);
  link.session.resolution_centideg = static_cast<int>(std::lround(resolution * 100.0));
  if (std::abs(resolution * 100.0 - link.session.resolution_centideg) > 1e-6) {
    read.fail("resolution",
              "must be 1.0, 0.5 or 0.25 (degrees), got " + std::to_string(resolution));
  }
  std::string units = "mm";
  read.text("units", &units);
  if (units != "mm" && units != "cm") {
    read.fail("units", "must be mm (8.18 m range) or cm (81.8 m range), got '" + units + "'");
  }
  link.session.units =
      units == "mm" ? sick_lms200::Units::kMillimetres : sick_lms200::Units::kCentimetres;
  read.text("frame_id", &options->message.frame_id);
  read.number("time_offset", &link.time_offset, -1.0, 1.0);
  read.flag("inverted", &options->message.inverted);
  read.number("reconnect_delay", &link.reconnect_delay, 0.01, 60.0);
  read.number("data_timeout", &link.data_timeout, 0.01, 60.0);
  read.allow("diagnostic_period");  // diagnostic_updater's own
  read.rejectUnknown();
  if (!read.ok()) {
    *error = read.errors();
    return false;
  }
  *error = sick_lms200::validateSessionOptions(link.session);
  return error->empty();
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "lms200_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  NodeOptions options;
  std::string error;
  if (!loadOptions(pnh, &options, &error)) {
    ROS_FATAL("lms200_node: bad parameter: %s", error.c_str());
    return 1;
  }
  ros::Publisher scan_pub = nh.advertise<sensor_msgs::LaserScan>("scan", 10);

  sick_lms200::ScannerLink link(
      options.link, [] { return ros::Time::now().toSec(); },
      [&](const sick_lms200::LaserScanData& scan) {
        scan_pub.publish(sick_lms200::toLaserScan(scan, options.message));
      });

  diagnostic_updater::Updater updater;
  updater.setHardwareID("LMS200 on " + options.link.port);
  const double expected_rate = sick_lms200::expectedScanRate(
      options.link.session.angle_deg, options.link.session.resolution_centideg,
      options.link.session.baud);
  LinkStats previous;
  ros::WallTime previous_time = ros::WallTime::now();
  updater.add("LMS200", [&](diagnostic_updater::DiagnosticStatusWrapper& status) {
    const LinkStats stats = link.stats();
    const ros::WallTime now = ros::WallTime::now();
    const double dt = std::max(1e-3, (now - previous_time).toSec());
    const double rate = (stats.scans - previous.scans) / dt;
    const uint64_t new_crc = stats.crc_errors - previous.crc_errors;
    const uint64_t new_losses = stats.link_losses - previous.link_losses;
    using diagnostic_msgs::DiagnosticStatus;
    if (stats.state != sick_lms200::LinkState::kStreaming) {
      status.summaryf(DiagnosticStatus::ERROR, "%s: %s", sick_lms200::linkStateName(stats.state),
                      stats.last_error.c_str());
    } else if (stats.have_status && sick_lms200::statusSeverity(stats.sensor_status) >=
                                        sick_lms200::StatusSeverity::kWarning) {
      status.summaryf(DiagnosticStatus::WARN, "sensor reports %s",
                      sick_lms200::describeStatus(stats.sensor_status).c_str());
    } else if (rate < 0.8 * expected_rate) {
      status.summaryf(DiagnosticStatus::WARN, "scan rate %.1f Hz below the expected %.1f Hz", rate,
                      expected_rate);
    } else if (new_crc > 0 || new_losses > 0) {
      status.summaryf(
          DiagnosticStatus::WARN, "%llu checksum errors and %llu link losses since the last report",
          static_cast<unsigned long long>(new_crc), static_cast<unsigned long long>(new_losses));
    } else {
      status.summary(DiagnosticStatus::OK, "streaming");
    }
    status.add("Link state", sick_lms200::linkStateName(stats.state));
    status.add("Port", options.link.port);
    status.add("Baud", stats.baud);
    status.add("Type", stats.type_string);
    status.add("Sensor status", stats.have_status ? sick_lms200::describeStatus(stats.sensor_status)
                                                  : std::string("unknown"));
    status.addf("Scan rate (Hz)", "%.2f", rate);
    status.addf("Expected scan rate (Hz)", "%.2f", expected_rate);
    status.add("Scans published", stats.scans);
    status.add("CRC errors", stats.crc_errors);
    status.add("Bad frames", stats.bad_frames);
    status.add("Discarded bytes", stats.discarded_bytes);
    status.add("Malformed scans", stats.malformed_scans);
    status.add("Scans dropped for sensor status", stats.status_rejected);
    status.add("Initialisations", stats.connects);
    status.add("Link losses", stats.link_losses);
    status.add("Last error", stats.last_error);
    previous = stats;
    previous_time = now;
  });

  std::atomic<bool> running{true};
  std::thread io([&] {
    sick_lms200::LinkState last_state = sick_lms200::LinkState::kDisconnected;
    std::string last_error;
    while (running) {
      link.spinOnce();
      const LinkStats stats = link.stats();
      if (stats.state != last_state || stats.last_error != last_error) {
        if (stats.state == sick_lms200::LinkState::kStreaming &&
            last_state != sick_lms200::LinkState::kStreaming) {
          ROS_INFO("lms200_node: %s streaming at %d baud (%s)", options.link.port.c_str(),
                   stats.baud, stats.type_string.c_str());
        } else if (stats.last_error != last_error && !stats.last_error.empty()) {
          ROS_WARN_THROTTLE(1.0, "lms200_node: %s", stats.last_error.c_str());
        }
        last_state = stats.state;
        last_error = stats.last_error;
      }
    }
  });

  ros::Rate rate(10.0);
  while (ros::ok()) {
    updater.update();
    ros::spinOnce();
    rate.sleep();
  }
  running = false;
  io.join();
  link.shutdown();
  return 0;
}
