// The node's intake: every scan (or features message, input: features)
// is checked on arrival (clock, pause, geometry, valid readings, stamp
// order), then waits in a tf2_ros::MessageFilter until odom → laser exists
// at its stamp (that covers odom → base_link and base_link → laser), at
// most scan_queue_size inputs. A transform never received, or base_link →
// laser late, is waited for at most tf_timeout (then the input is dropped
// and counted); odometry that has paused (logs record only motion) is
// waited for until its next sample. Inputs leave in arrival order: a ready
// one waits for the older ones. Each input released goes to the `released`
// hook with odom → base_link and base_link → its frame at its stamp; a scan
// from a laser mounted upside down (its z axis down in tf) is mirrored
// first, so that the map is not (features from one are dropped: their
// extractor saw the mirrored world).
//
// Owns the input subscriber (a WatchedSubscriber: every input discarded
// before the node took it is counted), both message filters, the waiting queue and
// the clock checks; counts every drop in the DropCounter it is given.
#pragma once

#include <ekf_slam/Features.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/Header.h>
#include <tf2_ros/message_filter.h>

#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/sensors/scan.h"
#include "ekf_slam_ros/slam_node/drop_counter.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"
#include "ekf_slam_ros/slam_node/transform_source.h"
#include "ekf_slam_ros/slam_node/watched_subscriber.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {

// One input waiting in the message filter for its transforms: a scan, or
// features extracted from one (input: features), with the scan's header.
struct PendingInput {
  std_msgs::Header header;
  std::optional<Scan> scan;
  std::optional<FeatureSet> features;
  ros::Time received;             // for the tf wait (clock time: data or sim)
  const void* message = nullptr;  // the message the filter holds (identity only)
  bool ready = false;             // its transforms exist; processed once the older ones are
  bool expired = false;           // dropped and counted; ignored on release
  // base_link → laser in 3-D at the stamp, set on release. An inverted
  // laser's scan has been mirrored by then (mirroredScan).
  ros_conversions::LaserMount mount;
};

class InputQueue {
 public:
  struct Hooks {
    std::function<bool()> paused;  // true: every input is dropped (kPaused)
    // The clock jumped back (a bag restarted); the tf buffer and the queue
    // have been emptied. The input that showed it is processed after.
    std::function<void()> clock_jumped;
    // An input whose transforms exist, in arrival order.
    std::function<void(const PendingInput&, const Pose2& odometry, const Pose2& laser)> released;
  };

  // Subscribes to params.scan_topic or params.features_topic (params.input).
  // `params`, `transforms` and `drops` must outlive the queue.
  InputQueue(ros::NodeHandle node, const SlamNodeParams& params, TransformSource& transforms,
             DropCounter& drops, Hooks hooks);

  // Empties both message filters and the inputs waiting in them.
  void clear();
  // Forgets the last accepted stamp (a new map takes any stamp).
  void restartStampOrder() { last_accepted_stamp_.reset(); }
  long received() const { return received_; }
  // Inputs waiting for their transforms now.
  long waiting() const { return static_cast<long>(waiting_.size()); }
  std::string topic() const;

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& message);
  void onFeatures(const Features::ConstPtr& message);
  // `count` inputs the subscriber discarded before the node took them.
  void onDiscarded(long count);
  // Common to both inputs: the clock and pause checks (false: dropped).
  bool accepting();
  // Hands a checked input to its message filter (`add`: the filter's add
  // for the message), or drops it for its stamp.
  void enqueue(PendingInput pending, const std::function<void()>& add);
  // The message filter's verdicts, on the node's thread: the transforms
  // exist at the input's stamp, or it was dropped (queue full, too old).
  void onTransformsReady(const void* message);
  void onTransformsFailed(const void* message, tf2_ros::FilterFailureReason reason);
  // Processes the ready inputs at the head of the queue, in arrival order.
  void releaseInOrder();
  void release(PendingInput pending);
  // Drops (and counts, once) inputs that have waited longer than tf_timeout
  // for a transform that is missing rather than merely behind.
  void expireWaiting();
  std::deque<PendingInput>::iterator find(const void* message);

  const SlamNodeParams& params_;
  TransformSource& transforms_;
  DropCounter& drops_;
  Hooks hooks_;
  // One of the two, by params.input.
  std::unique_ptr<WatchedSubscriber<sensor_msgs::LaserScan>> scan_subscriber_;
  std::unique_ptr<WatchedSubscriber<Features>> features_subscriber_;
  // Inputs wait for their transforms in a tf2_ros::MessageFilter (target
  // odom_frame, so that both odom → base_link and base_link → laser must
  // exist at the stamp); `waiting_` holds what the node knows of each, in
  // arrival order.
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::LaserScan>> scan_filter_;
  std::unique_ptr<tf2_ros::MessageFilter<Features>> features_filter_;
  std::deque<PendingInput> waiting_;
  std::optional<ros::Time> last_accepted_stamp_;  // newest input let into the filter
  ros::Time last_clock_;  // ros::Time::now() at the last input (jump-back detection)
  long received_ = 0;     // inputs received, dropped ones included
  ros::Timer drain_timer_;
};

}  // namespace ekf_slam
