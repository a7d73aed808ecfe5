#include "ekf_slam_ros/slam_node/transform_source.h"

#include <tf2/exceptions.h>

#include <algorithm>

#include <sstream>

#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {

TransformSource::TransformSource(double cache_time, double max_future)
    : cache_time_(cache_time), buffer_(ros::Duration(cache_time)), listener_(buffer_, max_future) {}

std::optional<ros::Time> TransformSource::latestStamp(const std::string& target,
                                                      const std::string& source) const {
  try {
    return buffer_.lookupTransform(target, source, ros::Time(0)).header.stamp;
  } catch (const tf2::TransformException&) {
    return std::nullopt;
  }
}

ros::Time TransformSource::dataTime(const std::string& target, const std::string& source) const {
  ros::Time reached = std::max(ros::Time::now(), listener_.newestReceived(target, source));
  const std::optional<ros::Time> latest = latestStamp(target, source);  // a chain of frames
  return latest && *latest > reached ? *latest : reached;
}

bool TransformSource::lookup(const std::string& target, const std::string& source,
                             const ros::Time& stamp, Pose2* pose, std::string* why,
                             bool* behind) const {
  geometry_msgs::Transform transform;
  if (!lookup(target, source, stamp, &transform, why, behind)) return false;
  *pose = ros_conversions::fromTransformMessage(transform);
  return true;
}

bool TransformSource::lookupMount(const std::string& target, const std::string& source,
                                  const ros::Time& stamp, ros_conversions::LaserMount* mount,
                                  std::string* why) const {
  geometry_msgs::Transform transform;
  if (!lookup(target, source, stamp, &transform, why, nullptr)) return false;
  *mount = ros_conversions::laserMountOf(transform);
  return true;
}

bool TransformSource::lookup(const std::string& target, const std::string& source,
                             const ros::Time& stamp, geometry_msgs::Transform* transform,
                             std::string* why, bool* behind) const {
  if (behind) *behind = false;
  const auto attempt = [&]() {
    *transform = buffer_.lookupTransform(target, source, stamp).transform;
  };
  try {
    attempt();
    return true;
  } catch (const tf2::TransformException& e) {
    std::ostringstream text;
    text.setf(std::ios::fixed);
    text.precision(3);
    text << target << " -> " << source << " at " << stamp.toSec();
    // How late: the newest transform there is, if any.
    try {
      const ros::Time latest = buffer_.lookupTransform(target, source, ros::Time(0)).header.stamp;
      if (latest.isZero()) {
        text << " (only a static transform? " << e.what() << ")";
      } else if (latest < stamp) {
        text << ": the newest is " << (stamp - latest).toSec() << " s older than the scan";
        if (behind) *behind = true;
      } else {
        // The tf listener runs on its own thread: the sample the first
        // attempt lacked (odometry resuming after a pause) may have arrived
        // since. Then the transform is there and nothing is missing.
        try {
          attempt();
          return true;
        } catch (const tf2::TransformException&) {
        }
        text << ": the scan is older than the transforms still buffered (" << e.what()
             << "); the buffer keeps tf_cache_time = " << cache_time_
             << " s before the newest transform: a node that falls further behind (a replay at "
                "a high rate on a loaded machine) needs a longer one";
      }
    } catch (const tf2::TransformException&) {
      text << ": never received (" << e.what() << ")";
    }
    *why = text.str();
    return false;
  }
}

}  // namespace ekf_slam
