#include "ekf_slam_ros/offline/log_input.h"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ekf_slam_core/io/carmen_log.h"
#include "ekf_slam_core/pipeline/odometry_track.h"
#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace {

std::string stripSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

// The earliest and the latest scan stamp (file order need not be time order).
void setStampRange(LogData* log) {
  if (log->scans.empty()) return;
  double lo = log->scans.front().scan.stamp, hi = lo;
  for (const LoggedScan& s : log->scans) {
    lo = std::min(lo, s.scan.stamp);
    hi = std::max(hi, s.scan.stamp);
  }
  log->first_stamp = lo;
  log->last_stamp = hi;
}

void finish(LogData* out, const OdometryTrack& track, double max_gap) {
  out->odometry_samples = static_cast<long>(track.size());
  double previous = -std::numeric_limits<double>::infinity();
  for (LoggedScan& s : out->scans) {
    if (track.poseAt(s.scan.stamp, max_gap, &s.odometry) != OdometryTrack::Lookup::kInterpolated) {
      ++out->odometry_gaps;
    }
    if (s.scan.stamp <= previous) ++out->scans_out_of_time_order;
    previous = s.scan.stamp;
  }
  setStampRange(out);
}

// Leaves out scans with a non-finite stamp or an odometry pose the pipeline
// cannot use (usableOdometry: not finite, or beyond 1,000 km), counted; the
// stamp range is taken over the rest. The pipeline then records every scan
// it is given, one trajectory line per scan.
void dropUnusable(LogData* log) {
  std::vector<LoggedScan> kept;
  kept.reserve(log->scans.size());
  for (size_t i = 0; i < log->scans.size(); ++i) {
    LoggedScan& s = log->scans[i];
    if (std::isfinite(s.scan.stamp) && usableOdometry(s.odometry)) {
      kept.push_back(std::move(s));
      continue;
    }
    if (log->unusable_scans++ == 0) {
      std::ostringstream what;
      what << "scan " << i << " (stamp " << s.scan.stamp << ", odometry " << s.odometry.x << " "
           << s.odometry.y << " " << s.odometry.theta << ")";
      log->first_unusable = what.str();
    }
  }
  log->scans.swap(kept);
  setStampRange(log);
}

}  // namespace

std::string readBag(const std::string& path, const InputOptions& options, LogData* out) {
  *out = LogData();
  LogData data;
  OdometryTrack track;
  const std::string odom_frame = stripSlash(options.odom_frame);
  const std::string base_frame = stripSlash(options.base_frame);
  // base_frame → child, in 3-D (an upside-down laser's scans are mirrored).
  std::vector<std::pair<std::string, ros_conversions::LaserMount>> static_children;
  // odometry_source tf: the transforms also go into a tf2 buffer holding the
  // whole log, and each scan's odometry is looked up there as the live node
  // looks it up (tf2's interpolation, the same doubles), so that a replay
  // of the bag through the node and this runner see identical inputs.
  tf2::BufferCore tf_buffer(ros::Duration(1.0e7));
  try {
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Read);
    // The laser mount from /tf_static first (a message or two at the start
    // of the bag). Where it is there and the odometry comes from /odom,
    // the main pass leaves /tf out: the real logs carry tens of thousands
    // of /tf messages that hold only odom → base_link, and deserialising
    // them cost a tenth of reading the bag. A mount on /tf_static is taken
    // over one on /tf.
    std::string laser_frame;
    {
      rosbag::View first_scan(bag, rosbag::TopicQuery(options.scan_topic));
      for (const rosbag::MessageInstance& m : first_scan) {
        const sensor_msgs::LaserScan::ConstPtr msg = m.instantiate<sensor_msgs::LaserScan>();
        if (msg) laser_frame = stripSlash(msg->header.frame_id);
        break;
      }
    }
    bool static_mount = laser_frame == base_frame;
    {
      rosbag::View statics(bag, rosbag::TopicQuery("/tf_static"));
      for (const rosbag::MessageInstance& m : statics) {
        const tf2_msgs::TFMessage::ConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();
        if (!msg) continue;
        for (const auto& t : msg->transforms) {
          if (stripSlash(t.header.frame_id) != base_frame) continue;
          const std::string child = stripSlash(t.child_frame_id);
          static_children.emplace_back(child, ros_conversions::laserMountOf(t.transform));
          static_mount |= child == laser_frame;
        }
      }
    }
    const bool read_tf = options.odometry_source == "tf" || !static_mount;
    std::vector<std::string> topics{options.scan_topic};
    if (options.odometry_source == "odom") topics.push_back(options.odom_topic);
    if (read_tf) topics.push_back("/tf");
    rosbag::View view(bag, rosbag::TopicQuery(topics));
    for (const rosbag::MessageInstance& m : view) {
      const std::string& topic = m.getTopic();
      if (topic == options.scan_topic) {
        const sensor_msgs::LaserScan::ConstPtr msg = m.instantiate<sensor_msgs::LaserScan>();
        if (!msg) return path + ": topic " + topic + " is not sensor_msgs/LaserScan";
        LoggedScan s;
        s.seq = msg->header.seq;
        s.stamp_ns = static_cast<int64_t>(msg->header.stamp.toNSec());
        s.scan = ros_conversions::fromLaserScan(*msg);
        if (data.laser_frame.empty()) data.laser_frame = stripSlash(msg->header.frame_id);
        data.scans.push_back(std::move(s));
      } else if (options.odometry_source == "odom" && topic == options.odom_topic) {
        const nav_msgs::Odometry::ConstPtr msg = m.instantiate<nav_msgs::Odometry>();
        if (!msg) return path + ": topic " + topic + " is not nav_msgs/Odometry";
        track.add(msg->header.stamp.toSec(), ros_conversions::fromPoseMessage(msg->pose.pose));
      } else if (topic == "/tf") {
        const tf2_msgs::TFMessage::ConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();
        if (!msg) continue;
        for (const auto& t : msg->transforms) {
          const std::string parent = stripSlash(t.header.frame_id);
          const std::string child = stripSlash(t.child_frame_id);
          const Pose2 pose = ros_conversions::fromTransformMessage(t.transform);
          if (options.odometry_source == "tf" && parent == odom_frame && child == base_frame) {
            track.add(t.header.stamp.toSec(), pose);
            tf_buffer.setTransform(t, "bag");
          } else if (parent == base_frame && !static_mount) {
            static_children.emplace_back(child, ros_conversions::laserMountOf(t.transform));
          }
        }
      }
    }
    bag.close();
  } catch (const rosbag::BagException& e) {
    return path + ": cannot read the bag (missing, truncated or corrupt): " + e.what();
  } catch (const std::exception& e) {
    return path + ": error while reading the bag: " + e.what();
  }
  if (data.scans.empty()) return path + ": no scans: topic " + options.scan_topic + " is empty";
  if (track.size() == 0) {
    return path + ": no odometry: " +
           (options.odometry_source == "odom"
                ? "topic " + options.odom_topic + " has no messages"
                : "tf has no " + odom_frame + " -> " + base_frame + " transform");
  }
  for (const auto& [child, mount] : static_children) {
    if (child == data.laser_frame) {
      data.laser_pose = mount.pose;
      data.laser_pose_found = true;
      data.laser_inverted = mount.inverted;
      data.laser_roll = mount.scan_roll;
      data.laser_pitch = mount.scan_pitch;
    }
  }
  // As the live node does: an upside-down laser's scans, as an upright one
  // at its place would see them; a tilted one's, as a level one would.
  if (data.laser_inverted) {
    for (LoggedScan& s : data.scans) s.scan = mirroredScan(s.scan);
  }
  if (data.laser_roll != 0.0 || data.laser_pitch != 0.0) {
    for (LoggedScan& s : data.scans)
      s.scan = levelledScan(s.scan, data.laser_roll, data.laser_pitch);
  }
  if (data.laser_frame == base_frame) data.laser_pose_found = true;  // laser at base_link
  track.finalize();
  // File order: by header.seq when the log numbers its scans, else as stored.
  const bool numbered = std::any_of(data.scans.begin(), data.scans.end(),
                                    [](const LoggedScan& s) { return s.seq != 0; });
  if (numbered) {
    std::stable_sort(data.scans.begin(), data.scans.end(),
                     [](const LoggedScan& a, const LoggedScan& b) { return a.seq < b.seq; });
  }
  finish(&data, track, options.max_odometry_gap);
  if (options.odometry_source == "tf") {
    for (LoggedScan& s : data.scans) {
      try {
        ros::Time stamp;
        stamp.fromNSec(static_cast<uint64_t>(s.stamp_ns));
        const geometry_msgs::TransformStamped t =
            tf_buffer.lookupTransform(odom_frame, base_frame, stamp);
        s.odometry = ros_conversions::fromTransformMessage(t.transform);
      } catch (const tf2::TransformException&) {
        // Before the first or after the last sample: the track's nearest.
      }
    }
  }
  dropUnusable(&data);
  *out = std::move(data);
  return "";
}

std::string readCarmen(const std::string& path, LogData* out) {
  *out = LogData();
  CarmenLog log;
  const std::string error = readCarmenLog(path, &log);
  if (!error.empty()) return error;
  if (log.lasers.empty()) return path + ": no laser scans (FLASER or ROBOTLASER1 lines)";
  LogData data;
  OdometryTrack track;
  uint32_t seq = 0;
  for (const CarmenLaser& laser : log.lasers) {
    LoggedScan s;
    s.seq = seq++;
    s.scan = laser.scan;
    track.add(laser.scan.stamp, laser.robot_odometry);  // each scan carries its odometry
    data.scans.push_back(std::move(s));
  }
  data.laser_pose = log.lasers.front().laser_in_robot;
  data.laser_pose_found = true;
  data.laser_frame = "laser";
  track.finalize();
  finish(&data, track, 1e-9);
  for (size_t i = 0; i < data.scans.size(); ++i)
    data.scans[i].odometry = log.lasers[i].robot_odometry;
  data.odometry_gaps = 0;
  dropUnusable(&data);
  *out = std::move(data);
  return "";
}

}  // namespace ekf_slam
