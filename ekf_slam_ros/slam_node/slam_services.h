// ekf_slam_node's services and rviz's initial pose: ~pause, ~resume, ~step
// (the supervised step mode, thesis §3.4.3), ~reset, ~smooth, ~save_map,
// ~load_map, and /initialpose. Each handler checks its request, asks the
// SLAM state (SlamControl) for the change, and answers with what it did.
//
// Threads: the quick handlers run on the spin thread with the scans. The
// slow ones (~smooth: a batch solve; ~save_map, ~load_map: files) run on a
// thread of their own, so that scans and map → odom keep flowing; they
// copy what they need of the state on the spin thread (runOnSpinThread),
// work on the copy, and hand the result back the same way. A result from a
// map that restarted meanwhile is dropped, and the reply says so.
//
// Owns the service servers, the initial pose subscriber, the slow
// services' queue and thread, and the run state the handlers set: paused,
// a step pending, the counts of steps and restarts.
#pragma once

#include <ekf_slam/LoadMap.h>
#include <ekf_slam/SaveMap.h>
#include <ekf_slam/StateFile.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/GetMap.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <ros/spinner.h>
#include <std_srvs/Trigger.h>

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_ros/slam_node/grid_output.h"
#include "ekf_slam_ros/slam_node/scan_outputs.h"
#include "ekf_slam_ros/slam_node/slam_control.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"

namespace ekf_slam {

class SlamServices {
 public:
  // Advertises the services under `private_node`, subscribes to
  // initialpose under `node`. Every reference must outlive the services.
  SlamServices(ros::NodeHandle node, ros::NodeHandle private_node, const SlamNodeParams& params,
               const OccupancyGridOptions& map, SlamControl& slam, ScanOutputs& outputs,
               GridOutput& grids);
  // Stops the slow services' thread (a handler waiting for the spin
  // thread gives up) before anything it uses goes.
  ~SlamServices();
  SlamServices(const SlamServices&) = delete;
  SlamServices& operator=(const SlamServices&) = delete;

  bool paused() const { return paused_; }
  long steps() const { return steps_done_; }
  long relocalisations() const { return relocalisations_; }
  // After each processed scan: a pending ~step was that scan, so the node
  // pauses again (the inputs waiting are dropped).
  void afterScan(const ros::Time& stamp, ScanOutcome outcome);
  // A new map: no step is pending.
  void cancelStep() { step_pending_ = false; }
  // What ~reset does, for `why` (logged): an empty map, published so; the
  // next scan starts a new one.
  void startNewMap(const std::string& why);

 private:
  bool onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  // One iteration on the next scan, then paused again; the move made while
  // paused is control, not a jump.
  bool onStep(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onSmooth(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onSaveMap(SaveMap::Request& request, SaveMap::Response& response);
  bool onLoadMap(LoadMap::Request& request, LoadMap::Response& response);
  // ~write_state / ~load_state: the whole SLAM state (srv/StateFile.srv).
  bool onWriteState(StateFile::Request& request, StateFile::Response& response);
  bool onLoadState(StateFile::Request& request, StateFile::Response& response);
  // dynamic_map (nav_msgs/GetMap, as gmapping and slam_toolbox offer it):
  // the grid last published on `map`; fails while there is none.
  bool onDynamicMap(nav_msgs::GetMap::Request&, nav_msgs::GetMap::Response& response);
  // The filter restarts at the given pose, the current landmarks (or the
  // loaded map) as its prior.
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped& message);
  std_msgs::Header mapHeader() const;  // the map frame, at the last scan's stamp
  // A slow handler's access to the state: `work` runs on the spin thread.
  // False (nothing done) when the node shuts down first.
  bool onSpinThread(const std::function<void()>& work) const;

  const SlamNodeParams& params_;
  OccupancyGridOptions map_options_;
  SlamControl& slam_;
  ScanOutputs& outputs_;
  GridOutput& grids_;
  ros::CallbackQueue slow_queue_;  // ~smooth, the saves and loads
  std::atomic<bool> closing_{false};
  std::vector<ros::ServiceServer> services_;
  std::unique_ptr<ros::AsyncSpinner> slow_thread_;
  ros::Subscriber initial_pose_subscriber_;
  bool paused_ = false;
  bool step_pending_ = false;  // ~step: pause again after the next scan
  long steps_done_ = 0;
  long relocalisations_ = 0;  // /initialpose messages taken
};

}  // namespace ekf_slam
