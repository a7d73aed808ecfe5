// feature_node: scan → `features` (ekf_slam/Features, stamped and framed as
// the scan) + `feature_markers` for rviz. The extraction is the core's
// extractFeatures with the `features:` section of the configuration (~slam,
// or the file config_file), the same code ekf_slam_node runs inside its
// pipeline.
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ekf_slam_ros/offline/slam_config.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"

namespace {

class FeatureNode {
 public:
  FeatureNode(ros::NodeHandle node, const ekf_slam::FeatureNodeParams& params,
              const ekf_slam::FeatureOptions& options)
      : options_(options) {
    features_ = node.advertise<ekf_slam::Features>("features", 10);
    markers_ = node.advertise<visualization_msgs::MarkerArray>("feature_markers", 10);
    scans_ = node.subscribe(params.scan_topic, 10, &FeatureNode::onScan, this);
  }

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& message) {
    const ekf_slam::FeatureSet features =
        ekf_slam::extractFeatures(ekf_slam::ros_conversions::fromLaserScan(*message), options_);
    if (!features.error.empty()) {
      ROS_WARN_THROTTLE(5.0, "feature_node: scan at %.3f rejected: %s",
                        message->header.stamp.toSec(), features.error.c_str());
      return;
    }
    features_.publish(ekf_slam::toFeaturesMessage(features, message->header));
    if (markers_.getNumSubscribers() > 0) {
      markers_.publish(ekf_slam::featureMarkers(features, message->header));
    }
  }

  ekf_slam::FeatureOptions options_;
  ros::Publisher features_, markers_;
  ros::Subscriber scans_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "feature_node");
  ros::NodeHandle node, private_node("~");
  ekf_slam::FeatureNodeParams params;
  std::string error;
  if (!ekf_slam::loadFeatureNodeParams(private_node, &params, &error)) {
    ROS_FATAL("feature_node: %s", error.c_str());
    return 1;
  }
  ekf_slam::SlamConfig config;
  std::string source;
  if (!ekf_slam::loadNodeSlamConfig(private_node, params.config_file, &config, &source, &error)) {
    ROS_FATAL("feature_node: bad configuration %s:\n%s", source.c_str(), error.c_str());
    return 1;
  }
  FeatureNode feature_node(node, params, config.pipeline.features);
  ros::spin();
  return 0;
}
