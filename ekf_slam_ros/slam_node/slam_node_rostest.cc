// ekf_slam_node on a real roscore (rostest): this test node is the robot. It
// drives a circle in a synthetic room (ray cast with the core's polygon
// world), publishing tf odom → base_link, tf base_link → laser and laser
// scans, then feeds the node bad input and calls its services.
//   BadInput.*: a scan full of NaN, a scan stamped in the past, scans while
//     base_link → laser is missing: the node keeps running, /diagnostics
//     counts each case, the log names the frames, the map is unchanged.
//   Services.*: pause / resume, save_map / reset / load_map, smooth.
//   RearLaser.*: a second laser behind the robot (scan_rear, laser_rear)
//     merged into the scans; bad, stale and unplaceable rear scans leave
//     the front scans mapped alone, counted and logged.
//   AScanLater*: a scan 3 s late is mapped within the node's tf buffer
//     (tf_cache_time) and dropped, naming the parameter, beyond it.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ekf_slam/AssociationReport.h>
#include <ekf_slam/Features.h>
#include <ekf_slam/LandmarkMap.h>
#include <ekf_slam/LoadMap.h>
#include <ekf_slam/SaveMap.h>
#include <ekf_slam/StateFile.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/GetMap.h>
#include <nav_msgs/MapMetaData.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/LaserScan.h>
#include <std_srvs/Trigger.h>
#include <sys/stat.h>
#include <tf2_ros/transform_broadcaster.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "ekf_slam_core/io/atomic_file.h"
#include "ekf_slam_core/io/grid_map_file.h"
#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/pipeline/slam_state.h"
#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

constexpr double kRate = 10.0;  // Hz, scans and tf
const char* kNode = "/ekf_slam";

// The robot: a circle of radius 1 m in a 8 m × 6 m room with three boxes,
// odometry = ground truth (the node's behaviour, not accuracy, is tested).
class Robot {
 public:
  Robot() {
    room_.addPolygon({Vector2(-4, -3), Vector2(4, -3), Vector2(4, 3), Vector2(-4, 3)});
    room_.addBox(Vector2(2.5, 1.5), 0.6, 0.4, 0.3);
    room_.addBox(Vector2(-2.5, -1.0), 0.5, 0.5);
    room_.addBox(Vector2(0.5, -2.2), 0.8, 0.3);
    scans_ = node_.advertise<sensor_msgs::LaserScan>("scan", 1000);
    rear_scans_ = node_.advertise<sensor_msgs::LaserScan>("scan_rear", 10);
  }
  ~Robot() { stop(); }

  void start() {
    running_ = true;
    thread_ = std::thread([this] { loop(); });
  }
  void stop() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }

  std::atomic<bool> publish_scans{true};     // good scans
  std::atomic<bool> publish_laser_tf{true};  // base_link → laser
  std::atomic<bool> publish_rear_tf{false};  // base_link → laser_rear
  // Good rear scans, stamped kRearLag before each front scan (the two
  // lasers are not synchronised).
  std::atomic<bool> publish_rear_scans{false};
  static constexpr double kRearLag = 0.05;  // s

  // Publishes one scan now with `stamp` and ranges transformed by `edit`.
  void publishScan(const ros::Time& stamp, const std::function<void(std::vector<float>*)>& edit) {
    sensor_msgs::LaserScan scan = makeScan(stamp);
    edit(&scan.ranges);
    scans_.publish(scan);
  }
  // Publishes one rear scan now with `stamp`, `frame` and ranges
  // transformed by `edit` (seen from the rear mount).
  void publishRearScan(const ros::Time& stamp, const std::string& frame,
                       const std::function<void(std::vector<float>*)>& edit) {
    sensor_msgs::LaserScan scan = makeScan(stamp, rear_in_base_, frame);
    edit(&scan.ranges);
    rear_scans_.publish(scan);
  }
  // Publishes one odom → base_link stamped `stamp` (the trajectory's pose then).
  void publishOdometry(const ros::Time& stamp) {
    tf_.sendTransform(transform(stamp, "odom", "base_link", poseAt((stamp - start_).toSec())));
  }
  ros::Time lastGoodStamp() {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_good_stamp_;
  }
  // rad/s around the circle: the test node's ~turn_rate (a test that needs
  // whole turns soon sets it higher), 0.15 by default.
  static double turnRate() {
    static const double rate = ros::param::param("~turn_rate", 0.15);
    return rate;
  }
  // odom → base_link (= the true pose in the odometry frame) at `stamp`.
  Pose2 odometryAt(const ros::Time& stamp) const { return poseAt((stamp - start_).toSec()); }
  bool wasScanStamp(const ros::Time& stamp) {
    std::lock_guard<std::mutex> lock(mutex_);
    return good_stamps_.count(stamp) > 0;
  }

 private:
  Pose2 poseAt(double t) const {
    const double radius = 1.0;  // m
    const double heading = turnRate() * t;
    return Pose2(radius * std::sin(heading), -radius * std::cos(heading), heading);
  }

  sensor_msgs::LaserScan makeScan(const ros::Time& stamp) {
    return makeScan(stamp, laser_in_base_, "laser");
  }
  sensor_msgs::LaserScan makeScan(const ros::Time& stamp, const Pose2& mount,
                                  const std::string& frame) {
    sim::SweepGeometry sweep;  // 181 beams over 180°, 8 m
    const double t = (stamp - start_).toSec();
    const Pose2 laser = compose(poseAt(t), mount);
    std::vector<double> ranges;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ranges = sim::simulateRanges(room_, laser, sweep, 0.005, &rng_);
    }
    sensor_msgs::LaserScan scan;
    scan.header.stamp = stamp;
    scan.header.frame_id = frame;
    scan.angle_min = sweep.angle_min;
    scan.angle_increment = sweep.angle_increment;
    scan.angle_max = sweep.angle_min + (sweep.count - 1) * sweep.angle_increment;
    scan.range_min = 0.05;
    scan.range_max = sweep.max_range;
    for (double r : ranges) scan.ranges.push_back(static_cast<float>(r));
    return scan;
  }

  geometry_msgs::TransformStamped transform(const ros::Time& stamp, const std::string& parent,
                                            const std::string& child, const Pose2& p) {
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = parent;
    t.child_frame_id = child;
    t.transform.translation.x = p.x;
    t.transform.translation.y = p.y;
    t.transform.rotation.z = std::sin(0.5 * p.theta);
    t.transform.rotation.w = std::cos(0.5 * p.theta);
    return t;
  }

  void loop() {
    // One trajectory for the whole process: a later test continues where the
    // previous one stopped, so the node never sees the odometry jump back.
    static const ros::Time process_start = ros::Time::now();
    start_ = process_start;
    ros::Rate rate(kRate);
    while (running_ && ros::ok()) {
      const ros::Time now = ros::Time::now();
      tf_.sendTransform(transform(now, "odom", "base_link", poseAt((now - start_).toSec())));
      if (publish_laser_tf) tf_.sendTransform(transform(now, "base_link", "laser", laser_in_base_));
      if (publish_rear_tf) {
        tf_.sendTransform(transform(now, "base_link", "laser_rear", rear_in_base_));
      }
      if (publish_rear_scans) {
        rear_scans_.publish(makeScan(now - ros::Duration(kRearLag), rear_in_base_, "laser_rear"));
      }
      if (publish_scans) {
        scans_.publish(makeScan(now));
        std::lock_guard<std::mutex> lock(mutex_);
        last_good_stamp_ = now;
        good_stamps_.insert(now);
      }
      rate.sleep();
    }
  }

  ros::NodeHandle node_;
  ros::Publisher scans_, rear_scans_;
  tf2_ros::TransformBroadcaster tf_;
  sim::PolygonWorld room_;
  const Pose2 laser_in_base_{0.16, 0.0, 0.0};   // LMS200 on a P3-DX: 16 cm ahead
  const Pose2 rear_in_base_{-0.251, 0.0, kPi};  // config/calibration_rear.yaml: facing backwards
  std::mt19937 rng_{42};
  std::mutex mutex_;
  ros::Time start_, last_good_stamp_;
  std::set<ros::Time> good_stamps_;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

// Everything the node publishes that the tests look at.
class Observer {
 public:
  Observer() {
    subscribers_.push_back(node_.subscribe("/diagnostics", 50, &Observer::onDiagnostics, this));
    subscribers_.push_back(node_.subscribe("landmark_map", 10, &Observer::onMap, this));
    subscribers_.push_back(node_.subscribe("pose", 50, &Observer::onPose, this));
    // Every node publishes its log on /rosout directly (no rosout aggregator needed).
    subscribers_.push_back(node_.subscribe("/rosout", 500, &Observer::onLog, this));
    subscribers_.push_back(node_.subscribe("map", 1, &Observer::onGrid, this));
    subscribers_.push_back(node_.subscribe("map_metadata", 1, &Observer::onMetadata, this));
    subscribers_.push_back(node_.subscribe("features", 10, &Observer::onFeatures, this));
    subscribers_.push_back(node_.subscribe("association", 10, &Observer::onAssociation, this));
    subscribers_.push_back(node_.subscribe("smoothed_path", 1, &Observer::onSmoothedPath, this));
  }
  // The test's spinner threads may be inside a callback right now: shutting
  // a subscription down waits for its running callback and stops new ones,
  // so the members below outlive every callback that touches them.
  ~Observer() {
    for (ros::Subscriber& subscriber : subscribers_) subscriber.shutdown();
  }
  Observer(const Observer&) = delete;
  Observer& operator=(const Observer&) = delete;

  // The node's diagnostic value `key` as a number (NaN when not reported yet).
  double diagnostic(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = diagnostics_.find(key);
    return it == diagnostics_.end() ? std::nan("") : std::atof(it->second.c_str());
  }
  std::string diagnosticText(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = diagnostics_.find(key);
    return it == diagnostics_.end() ? "" : it->second;
  }
  long diagnosticsReceived() {
    std::lock_guard<std::mutex> lock(mutex_);
    return diagnostics_received_;
  }
  ekf_slam::LandmarkMap map() {
    std::lock_guard<std::mutex> lock(mutex_);
    return map_;
  }
  long maps() {
    std::lock_guard<std::mutex> lock(mutex_);
    return maps_;
  }
  long poses() {
    std::lock_guard<std::mutex> lock(mutex_);
    return poses_;
  }
  ros::Time lastPoseStamp() {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_pose_stamp_;
  }
  // A log line of the node has both texts.
  bool hasLogged(const std::string& a, const std::string& b) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const std::string& line : log_) {
      if (line.find(a) != std::string::npos && line.find(b) != std::string::npos) return true;
    }
    return false;
  }
  // The same, a test failure (with what was logged) when there is none.
  bool logged(const std::string& a, const std::string& b) {
    if (hasLogged(a, b)) return true;
    std::lock_guard<std::mutex> lock(mutex_);
    ADD_FAILURE() << "no log line of " << kNode << " with '" << a << "' and '" << b << "' among "
                  << log_.size() << " lines from it (" << other_lines_ << " from other nodes)";
    return false;
  }
  nav_msgs::OccupancyGrid grid() {
    std::lock_guard<std::mutex> lock(mutex_);
    return grid_;
  }
  long grids() {
    std::lock_guard<std::mutex> lock(mutex_);
    return grids_;
  }
  nav_msgs::MapMetaData metadata() {
    std::lock_guard<std::mutex> lock(mutex_);
    return metadata_;
  }
  ekf_slam::Features features() {
    std::lock_guard<std::mutex> lock(mutex_);
    return features_;
  }
  ekf_slam::AssociationReport association() {
    std::lock_guard<std::mutex> lock(mutex_);
    return association_;
  }
  geometry_msgs::PoseWithCovarianceStamped pose() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pose_;
  }
  size_t smoothedPoses() {
    std::lock_guard<std::mutex> lock(mutex_);
    return smoothed_poses_;
  }

 private:
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray& array) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const diagnostic_msgs::DiagnosticStatus& status : array.status) {
      if (status.name.find("EKF-SLAM") == std::string::npos) continue;
      ++diagnostics_received_;
      for (const diagnostic_msgs::KeyValue& kv : status.values) diagnostics_[kv.key] = kv.value;
    }
  }
  void onMap(const ekf_slam::LandmarkMap& map) {
    std::lock_guard<std::mutex> lock(mutex_);
    map_ = map;
    ++maps_;
  }
  void onPose(const geometry_msgs::PoseWithCovarianceStamped& pose) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++poses_;
    last_pose_stamp_ = pose.header.stamp;
    pose_ = pose;
  }
  void onLog(const rosgraph_msgs::Log& log) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (log.name == kNode) {
      log_.push_back(log.msg);
    } else {
      ++other_lines_;
    }
  }
  void onGrid(const nav_msgs::OccupancyGrid& grid) {
    std::lock_guard<std::mutex> lock(mutex_);
    grid_ = grid;
    ++grids_;
  }
  void onMetadata(const nav_msgs::MapMetaData& metadata) {
    std::lock_guard<std::mutex> lock(mutex_);
    metadata_ = metadata;
  }
  void onFeatures(const ekf_slam::Features& features) {
    std::lock_guard<std::mutex> lock(mutex_);
    features_ = features;
  }
  void onAssociation(const ekf_slam::AssociationReport& report) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!report.observations.empty()) association_ = report;
  }
  void onSmoothedPath(const nav_msgs::Path& path) {
    std::lock_guard<std::mutex> lock(mutex_);
    smoothed_poses_ = path.poses.size();
  }

  ros::NodeHandle node_;
  std::vector<ros::Subscriber> subscribers_;
  std::mutex mutex_;
  std::map<std::string, std::string> diagnostics_;
  long diagnostics_received_ = 0;
  ekf_slam::LandmarkMap map_;
  long maps_ = 0, poses_ = 0;
  ros::Time last_pose_stamp_;
  geometry_msgs::PoseWithCovarianceStamped pose_;
  ekf_slam::Features features_;
  ekf_slam::AssociationReport association_;
  std::vector<std::string> log_;
  long other_lines_ = 0;
  nav_msgs::OccupancyGrid grid_;
  long grids_ = 0;
  nav_msgs::MapMetaData metadata_;
  size_t smoothed_poses_ = 0;
};

// Waits (wall time) until `condition` holds; false on timeout. `seconds` is
// what an idle machine needs; the wait allows six times that, since these
// tests must pass beside other work (a condition met returns at once).
constexpr double kLoadAllowance = 6.0;
bool waitFor(const std::function<bool()>& condition, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(kLoadAllowance * seconds);
  while (ros::WallTime::now() < end) {
    if (condition()) return true;
    ros::WallDuration(0.05).sleep();
  }
  return condition();
}

int confirmedLandmarks(const ekf_slam::LandmarkMap& map) {
  int n = 0;
  for (const auto& l : map.landmarks) n += !l.tentative;
  return n;
}

bool sameLandmarks(const ekf_slam::LandmarkMap& a, const ekf_slam::LandmarkMap& b) {
  if (a.landmarks.size() != b.landmarks.size()) return false;
  for (size_t i = 0; i < a.landmarks.size(); ++i) {
    const auto &p = a.landmarks[i], &q = b.landmarks[i];
    if (p.id != q.id || p.x != q.x || p.y != q.y || p.covariance != q.covariance) return false;
  }
  return true;
}

// Whether a grid on `map` and a grid file hold the same cells (below).
bool sameGrid(const nav_msgs::OccupancyGrid& map, const GridMapFile& file);

class SlamNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(ros::service::waitForService(std::string(kNode) + "/reset", ros::Duration(30.0)))
        << "ekf_slam_node did not come up";
    robot_.start();
    ASSERT_TRUE(waitFor([&] { return confirmedLandmarks(observer_.map()) >= 3; }, 30.0))
        << "no map built from the synthetic room: " << observer_.map().landmarks.size()
        << " landmarks";
  }
  void TearDown() override { robot_.stop(); }

  template <typename Service>
  bool call(const std::string& name, Service* service) {
    return ros::service::call(std::string(kNode) + "/" + name, *service);
  }
  bool trigger(const std::string& name) {
    std_srvs::Trigger trigger;
    return call(name, &trigger) && trigger.response.success;
  }
  // Waits until a diagnostics report newer than now has arrived.
  bool freshDiagnostics() {
    const long seen = observer_.diagnosticsReceived();
    return waitFor([&] { return observer_.diagnosticsReceived() >= seen + 2; }, 5.0);
  }

  // Pause stops the iterations and counts the scans dropped; resume starts
  // them again.
  void expectPauseAndResume() {
    ASSERT_TRUE(trigger("pause"));
    ros::WallDuration(0.5).sleep();
    ASSERT_TRUE(freshDiagnostics());
    const double iterations = observer_.diagnostic("iterations");
    const double paused_drops = observer_.diagnostic("dropped: paused");
    ros::WallDuration(1.5).sleep();
    ASSERT_TRUE(freshDiagnostics());
    EXPECT_EQ(observer_.diagnostic("iterations"), iterations);
    EXPECT_GE(observer_.diagnostic("dropped: paused"), paused_drops + 10);
    ASSERT_TRUE(trigger("resume"));
    EXPECT_TRUE(waitFor([&] { return observer_.diagnostic("iterations") > iterations + 5; }, 5.0));
  }
  // ~save_map to `path` while paused: the grid on map is saved bit for bit
  // to `grid_path`, read back into `file`.
  void saveShownGrid(const std::string& path, const std::string& grid_path, GridMapFile* file) {
    ASSERT_TRUE(trigger("pause"));
    ros::WallDuration(1.5).sleep();
    const nav_msgs::OccupancyGrid shown = observer_.grid();
    ekf_slam::SaveMap save;
    save.request.path = path;
    ASSERT_TRUE(call("save_map", &save));
    ASSERT_TRUE(save.response.success) << save.response.message;
    EXPECT_EQ(save.response.grid_path, grid_path);
    ASSERT_EQ(readGridMap(save.response.grid_path, file), "");
    EXPECT_TRUE(sameGrid(shown, *file)) << "the saved grid is not the one on map";
  }
  // map_metadata describes the grid on map (after ~smooth and load_map too,
  // with or without the live map).
  void expectMetadataOfTheShownGrid() {
    EXPECT_TRUE(waitFor(
        [&] {
          const nav_msgs::MapMetaData m = observer_.metadata();
          const nav_msgs::MapMetaData shown = observer_.grid().info;
          return m.width == shown.width && m.height == shown.height &&
                 m.resolution == shown.resolution &&
                 m.origin.position.x == shown.origin.position.x &&
                 m.origin.position.y == shown.origin.position.y;
        },
        5.0))
        << "map_metadata " << observer_.metadata().width << " x " << observer_.metadata().height
        << " does not describe the grid on map, " << observer_.grid().info.width << " x "
        << observer_.grid().info.height;
  }
  // ~smooth: a smoothed path with one pose per scan since the load, and a
  // grid with the room's walls and free space.
  void expectSmoothedGrid() {
    std_srvs::Trigger smooth;
    ASSERT_TRUE(call("smooth", &smooth));
    ASSERT_TRUE(smooth.response.success) << smooth.response.message;
    EXPECT_TRUE(waitFor([&] { return observer_.smoothedPoses() > 10; }, 3.0));
    ASSERT_TRUE(waitFor([&] { return observer_.grid().info.width > 0; }, 3.0));
    const nav_msgs::OccupancyGrid grid = observer_.grid();
    EXPECT_EQ(grid.header.frame_id, "map");
    EXPECT_NEAR(grid.info.resolution, 0.05, 1e-6);
    int occupied = 0, free_cells = 0;
    for (int8_t v : grid.data) {
      occupied += v > 65;
      free_cells += v >= 0 && v < 35;
    }
    EXPECT_GT(occupied, 50) << "the room's walls";
    EXPECT_GT(free_cells, occupied) << "the room's inside";
    expectMetadataOfTheShownGrid();
  }

  Observer observer_;
  Robot robot_;
};

geometry_msgs::Pose poseMessage(const Pose2& pose) {
  geometry_msgs::Pose message;
  message.position.x = pose.x;
  message.position.y = pose.y;
  message.orientation.z = std::sin(0.5 * pose.theta);
  message.orientation.w = std::cos(0.5 * pose.theta);
  return message;
}

// A wall and a θ-only wall on the map's first two points, added to a saved
// map file (so that a load brings lines too) …
void addLines(LandmarkMapFile* file) {
  LineLandmarkRecord wall;
  wall.id = 1000;
  wall.p = 2.5;
  wall.theta = -0.75;
  wall.covariance << 4e-4, 1e-5, 1e-5, 1e-4;
  wall.observations = 6;
  wall.has_extent = true;
  wall.s_max = 3.0;
  file->lines.push_back(wall);
  LineAngleRecord direction;
  direction.id = 1001;
  direction.theta = 1.25;
  direction.variance = 2e-4;
  direction.endpoint_ids[0] = file->landmarks[0].id;
  direction.endpoint_ids[1] = file->landmarks[1].id;
  file->line_angles.push_back(direction);
}

// … and found again in the map the node publishes after the load.
void expectAddedLines(const ekf_slam::LandmarkMap& loaded) {
  ASSERT_EQ(loaded.lines.size(), 1u);
  EXPECT_EQ(loaded.lines[0].id, 1000);
  EXPECT_EQ(loaded.lines[0].p, 2.5);
  EXPECT_EQ(loaded.lines[0].theta, -0.75);
  EXPECT_EQ(loaded.lines[0].covariance[1], 1e-5);
  EXPECT_EQ(loaded.lines[0].observations, 6);
  ASSERT_EQ(loaded.line_angles.size(), 1u);
  EXPECT_EQ(loaded.line_angles[0].id, 1001);
  EXPECT_EQ(loaded.line_angles[0].theta, 1.25);
  EXPECT_EQ(loaded.line_angles[0].variance, 2e-4);
}

TEST_F(SlamNodeTest, BadInputIsCountedLoggedAndLeavesTheMapUnchanged) {
  // Freeze the map: no good scans while the bad ones go in (odometry goes on).
  robot_.publish_scans = false;
  ros::WallDuration(1.0).sleep();  // queued scans processed
  ASSERT_TRUE(freshDiagnostics());
  const ekf_slam::LandmarkMap before = observer_.map();
  const long maps_before = observer_.maps();
  const double nan_before = observer_.diagnostic("dropped: too few valid readings");
  const double past_before = observer_.diagnostic("dropped: stamp not increasing");
  const double laser_before = observer_.diagnostic("dropped: laser transform missing");
  const double geometry_before = observer_.diagnostic("dropped: bad scan geometry");
  const double future_before = observer_.diagnostic("dropped: stamp in the future");
  const double iterations_before = observer_.diagnostic("iterations");
  ASSERT_FALSE(std::isnan(nan_before));

  // 1. A scan full of NaN.
  robot_.publishScan(ros::Time::now(), [](std::vector<float>* r) {
    std::fill(r->begin(), r->end(), std::numeric_limits<float>::quiet_NaN());
  });
  // 2. A good-looking scan stamped 1 s before the last one.
  robot_.publishScan(robot_.lastGoodStamp() - ros::Duration(1.0), [](std::vector<float>*) {});
  // 3. A scan stamped 10⁶ s ahead of the clock: refused, and not the
  // reference for the later scans (mapping resumes below).
  robot_.publishScan(ros::Time::now() + ros::Duration(1.0e6), [](std::vector<float>*) {});
  // 4. A scan ten readings short of what its angle fields give.
  robot_.publishScan(ros::Time::now(), [](std::vector<float>* r) { r->resize(r->size() - 10); });
  // 5. Scans while base_link → laser is missing (odom → base_link still there).
  robot_.publish_laser_tf = false;
  ros::WallDuration(0.5).sleep();  // the last laser transform is now older than any new scan
  for (int i = 0; i < 5; ++i) {
    robot_.publishScan(ros::Time::now(), [](std::vector<float>*) {});
    ros::WallDuration(0.1).sleep();
  }
  // Past tf_timeout (0.3 s) for the last one before the transform comes back,
  // so that no waiting scan can be interpolated across the gap.
  ros::WallDuration(1.0).sleep();

  ASSERT_TRUE(freshDiagnostics());
  EXPECT_GE(observer_.diagnostic("dropped: too few valid readings"), nan_before + 1);
  EXPECT_GE(observer_.diagnostic("dropped: stamp not increasing"), past_before + 1);
  EXPECT_GE(observer_.diagnostic("dropped: laser transform missing"), laser_before + 5);
  EXPECT_GE(observer_.diagnostic("dropped: bad scan geometry"), geometry_before + 1);
  EXPECT_GE(observer_.diagnostic("dropped: stamp in the future"), future_before + 1);
  EXPECT_TRUE(observer_.logged("stamp in the future", "ahead of the clock"));
  EXPECT_TRUE(observer_.logged("bad scan geometry", "171 ranges"))
      << "the log must name the range count and what the angles give";
  EXPECT_EQ(observer_.diagnostic("iterations"), iterations_before);
  EXPECT_TRUE(observer_.logged("laser transform missing", "base_link -> laser"))
      << "the log must name the missing frames";
  EXPECT_TRUE(observer_.logged("stamp not increasing", "before"));
  EXPECT_TRUE(observer_.logged("too few valid readings", "0 of 181"));
  // The map: no new version published, the last one equal to before.
  EXPECT_EQ(observer_.maps(), maps_before);
  EXPECT_TRUE(sameLandmarks(observer_.map(), before));

  // Still alive and mapping once the input is good again.
  robot_.publish_laser_tf = true;
  robot_.publish_scans = true;
  const ros::Time resumed = ros::Time::now();
  EXPECT_TRUE(waitFor([&] { return observer_.lastPoseStamp() > resumed; }, 5.0));
  EXPECT_TRUE(waitFor([&] { return observer_.diagnostic("iterations") > iterations_before; }, 5.0));
  EXPECT_GT(observer_.maps(), maps_before);
}

// A burst of scans, far more than the node's subscriber queue holds
// (subscriber_queue_size 3 in slam_node_tf_cache.test): those the node had
// no time to take are discarded and counted, none is lost uncounted.
TEST_F(SlamNodeTest, ABurstBeyondTheSubscriberQueueIsCounted) {
  int capacity = 1000;
  ros::param::get(std::string(kNode) + "/subscriber_queue_size", capacity);
  if (capacity > 10) GTEST_SKIP() << "subscriber_queue_size " << capacity << ": no burst fills it";
  robot_.publish_scans = false;
  ros::WallDuration(0.5).sleep();  // queued scans processed
  ASSERT_TRUE(freshDiagnostics());
  const double received_before = observer_.diagnostic("scans received");
  const double full_before = observer_.diagnostic("dropped: subscriber queue full");
  ASSERT_FALSE(std::isnan(full_before));
  const int kBurst = 300;
  const ros::Time first = ros::Time::now();
  for (int i = 0; i < kBurst; ++i) {
    robot_.publishScan(first + ros::Duration(0.0001 * i), [](std::vector<float>*) {});
  }
  EXPECT_TRUE(waitFor(
      [&] { return observer_.diagnostic("scans received") >= received_before + kBurst; }, 5.0));
  ros::WallDuration(1.5).sleep();  // nothing more arrives
  ASSERT_TRUE(freshDiagnostics());
  EXPECT_EQ(observer_.diagnostic("scans received"), received_before + kBurst);
  EXPECT_GT(observer_.diagnostic("dropped: subscriber queue full"), full_before);
  EXPECT_TRUE(observer_.logged("subscriber queue full", "subscriber_queue_size"))
      << "the log must name the parameter";
  robot_.publish_scans = true;
  const ros::Time resumed = ros::Time::now();
  EXPECT_TRUE(waitFor([&] { return observer_.lastPoseStamp() > resumed; }, 5.0));
}

// One odom → base_link stamped 10⁶ s ahead among the normal ones. tf2's
// buffer would keep it as the newest transform and refuse every later one as
// old data, losing the odometry for 11 days; the node's listener refuses it
// instead, counts it, and mapping goes on with the next scan.
TEST_F(SlamNodeTest, AFutureOdometryTransformIsRefusedAndMappingContinues) {
  ASSERT_TRUE(freshDiagnostics());
  const double future_before = observer_.diagnostic("dropped tf: stamp in the future");
  const double missing_before = observer_.diagnostic("dropped: odom transform missing");
  ASSERT_FALSE(std::isnan(future_before));
  robot_.publishOdometry(ros::Time::now() + ros::Duration(1.0e6));
  ros::WallDuration(0.2).sleep();
  const ros::Time after = ros::Time::now();
  EXPECT_TRUE(waitFor([&] { return observer_.lastPoseStamp() > after; }, 2.0))
      << "no pose for a scan after the future transform: the odometry was lost";
  ASSERT_TRUE(freshDiagnostics());
  EXPECT_GE(observer_.diagnostic("dropped tf: stamp in the future"), future_before + 1);
  EXPECT_LE(observer_.diagnostic("dropped: odom transform missing"), missing_before + 1);
  EXPECT_TRUE(observer_.logged("tf stamp in the future", "odom -> base_link"))
      << "the log must name the frames";
}

// A scan that reaches the node 3 s after its stamp, while the odometry went
// on: the node buffers tf_cache_time seconds of transforms before the newest
// one. With tf2's 10 s (slam_node_services.test) the scan is mapped; with
// 2 s (slam_node_tf_cache.test: a node that fell that far behind) it is
// dropped, counted, and the log names the parameter to raise.
TEST_F(SlamNodeTest, AScanLaterThanTfCacheTimeIsDroppedNamingItAndMappedWithin) {
  double cache_time = 10.0;
  ros::param::get(std::string(kNode) + "/tf_cache_time", cache_time);
  const double kLate = 3.0;  // s
  robot_.publish_scans = false;
  ros::WallDuration(0.5).sleep();  // queued scans processed
  ASSERT_TRUE(freshDiagnostics());
  const double missing_before = observer_.diagnostic("dropped: odom transform missing");
  const double iterations_before = observer_.diagnostic("iterations");
  ASSERT_FALSE(std::isnan(missing_before));
  const ros::Time stamp = ros::Time::now();
  ros::WallDuration(kLate).sleep();  // odometry and the laser mount go on at 10 Hz
  robot_.publishScan(stamp, [](std::vector<float>*) {});
  if (cache_time > kLate + 1.0) {
    EXPECT_TRUE(waitFor([&] { return observer_.lastPoseStamp() == stamp; }, 3.0))
        << "a scan " << kLate << " s late was not mapped with tf_cache_time " << cache_time;
    ASSERT_TRUE(freshDiagnostics());
    EXPECT_EQ(observer_.diagnostic("dropped: odom transform missing"), missing_before);
    EXPECT_GT(observer_.diagnostic("iterations"), iterations_before);
  } else {
    EXPECT_TRUE(waitFor(
        [&] { return observer_.diagnostic("dropped: odom transform missing") > missing_before; },
        3.0))
        << "a scan " << kLate << " s late was not dropped with tf_cache_time " << cache_time;
    EXPECT_NE(observer_.lastPoseStamp(), stamp);
    EXPECT_EQ(observer_.diagnostic("iterations"), iterations_before);
    EXPECT_TRUE(observer_.logged("odom transform missing", "tf_cache_time = 2"))
        << "the log must name the parameter and its value";
  }
  // Mapping goes on with the next scans.
  robot_.publish_scans = true;
  const ros::Time resumed = ros::Time::now();
  EXPECT_TRUE(waitFor([&] { return observer_.lastPoseStamp() > resumed; }, 5.0));
}

TEST_F(SlamNodeTest, OutputsCarryTheScansStampsAndFrames) {
  ros::WallDuration(1.0).sleep();
  // Data time: every output is stamped with the stamp of a scan the robot sent.
  const ekf_slam::Features features = observer_.features();
  EXPECT_EQ(features.header.frame_id, "laser");
  EXPECT_TRUE(robot_.wasScanStamp(features.header.stamp)) << features.header.stamp;
  EXPECT_FALSE(features.lines.empty()) << "a room has walls";
  const geometry_msgs::PoseWithCovarianceStamped pose = observer_.pose();
  EXPECT_EQ(pose.header.frame_id, "map");
  EXPECT_TRUE(robot_.wasScanStamp(pose.header.stamp)) << pose.header.stamp;
  EXPECT_GT(pose.pose.covariance[0], 0.0);
  const ekf_slam::LandmarkMap map = observer_.map();
  EXPECT_EQ(map.header.frame_id, "map");
  EXPECT_TRUE(robot_.wasScanStamp(map.header.stamp));
  const ekf_slam::AssociationReport association = observer_.association();
  EXPECT_EQ(association.header.frame_id, "laser");
  EXPECT_TRUE(robot_.wasScanStamp(association.header.stamp));
  int matched = 0;
  for (const auto& o : association.observations) {
    if (o.decision != "matched") continue;
    ++matched;
    ASSERT_FALSE(o.candidates.empty());
    EXPECT_LT(o.candidates[0].mahalanobis_sq, o.gate);
  }
  EXPECT_GT(matched, 0) << "a corner seen again is matched";
}

// slam.launch rear_scan:=scan_rear (test/slam_node_rear_input.test).
TEST_F(SlamNodeTest, RearLaserIsMergedAndBadRearInputLeavesTheScansAlone) {
  // Good rear scans: merged, and the filter sees behind the robot.
  robot_.publish_rear_tf = true;
  robot_.publish_rear_scans = true;
  ASSERT_TRUE(
      waitFor([&] { return observer_.diagnostic("scans merged with a rear scan") > 20; }, 10.0))
      << "no scans merged: " << observer_.diagnosticText("scans merged with a rear scan");
  auto behind = [&] {
    const ekf_slam::AssociationReport report = observer_.association();
    if (report.header.frame_id != "base_link") return false;
    for (const auto& o : report.observations) {
      if (std::abs(o.bearing) > degToRad(100.0)) return true;
    }
    return false;
  };
  EXPECT_TRUE(waitFor(behind, 10.0))
      << "no observation behind the robot in the association reports (frame '"
      << observer_.association().header.frame_id << "')";
  EXPECT_EQ(observer_.diagnostic("rear scans refused"), 0.0);

  // Bad rear input; the front scans go on.
  robot_.publish_rear_scans = false;
  ros::WallDuration(0.6).sleep();
  ASSERT_TRUE(freshDiagnostics());
  const double refused_before = observer_.diagnostic("rear scans refused");
  const double stale_before =
      observer_.diagnostic("scans without the rear laser: none within rear_scan_tolerance");
  const double unplaced_before =
      observer_.diagnostic("scans without the rear laser: rear transforms missing");
  const double merged_before = observer_.diagnostic("scans merged with a rear scan");
  const double iterations_before = observer_.diagnostic("iterations");
  ASSERT_FALSE(std::isnan(stale_before));
  // 1. A rear scan ten readings short of its angle fields, and one stamped
  // 10⁶ s ahead: refused on arrival.
  robot_.publishRearScan(ros::Time::now(), "laser_rear",
                         [](std::vector<float>* r) { r->resize(r->size() - 10); });
  robot_.publishRearScan(ros::Time::now() + ros::Duration(1.0e6), "laser_rear",
                         [](std::vector<float>*) {});
  // 2. Rear scans 0.5 s older than the scans (beyond rear_scan_tolerance,
  // 0.2 s): the scans are mapped alone.
  for (int i = 0; i < 10; ++i) {
    robot_.publishRearScan(ros::Time::now() - ros::Duration(0.5), "laser_rear",
                           [](std::vector<float>*) {});
    ros::WallDuration(0.1).sleep();
  }
  ros::WallDuration(0.6).sleep();
  // 3. Rear scans in a frame tf does not know: mapped alone.
  for (int i = 0; i < 10; ++i) {
    robot_.publishRearScan(ros::Time::now(), "laser_nowhere", [](std::vector<float>*) {});
    ros::WallDuration(0.1).sleep();
  }
  // 4. Rear scans full of NaN and +inf: merged, adding nothing.
  for (int i = 0; i < 5; ++i) {
    robot_.publishRearScan(ros::Time::now(), "laser_rear", [i](std::vector<float>* r) {
      std::fill(
          r->begin(), r->end(),
          i % 2 ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity());
    });
    ros::WallDuration(0.1).sleep();
  }
  ros::WallDuration(0.5).sleep();

  ASSERT_TRUE(freshDiagnostics());
  EXPECT_GE(observer_.diagnostic("rear scans refused"), refused_before + 2);
  EXPECT_GE(observer_.diagnostic("scans without the rear laser: none within rear_scan_tolerance"),
            stale_before + 3);
  EXPECT_GE(observer_.diagnostic("scans without the rear laser: rear transforms missing"),
            unplaced_before + 3);
  EXPECT_GE(observer_.diagnostic("scans merged with a rear scan"), merged_before + 1);
  EXPECT_GT(observer_.diagnostic("iterations"), iterations_before + 10)
      << "the scans must be mapped alone meanwhile";
  EXPECT_TRUE(observer_.logged("rear scan", "refused"));
  EXPECT_TRUE(observer_.logged("used without the rear laser", "rear_scan_tolerance"));
  EXPECT_TRUE(observer_.logged("used without the rear laser", "laser_nowhere"))
      << "the log must name the frame whose transform is missing";

  // Merged again once the rear laser is back.
  const double merged_after = observer_.diagnostic("scans merged with a rear scan");
  robot_.publish_rear_scans = true;
  EXPECT_TRUE(waitFor(
      [&] { return observer_.diagnostic("scans merged with a rear scan") > merged_after + 5; },
      5.0));
  const ros::Time resumed = ros::Time::now();
  EXPECT_TRUE(waitFor([&] { return observer_.lastPoseStamp() > resumed; }, 5.0));
}

TEST_F(SlamNodeTest, PauseResumeSaveResetLoadAndSmooth) {
  ASSERT_NO_FATAL_FAILURE(expectPauseAndResume());

  // Save while paused (the map stands still), then compare with the file.
  ASSERT_TRUE(trigger("pause"));
  ros::WallDuration(0.5).sleep();
  const ekf_slam::LandmarkMap saved = observer_.map();
  ASSERT_GE(saved.landmarks.size(), 3u);
  char path[] = "/tmp/slam_node_map_XXXXXX";
  const int fd = ::mkstemp(path);
  ASSERT_GE(fd, 0);
  ::close(fd);
  ekf_slam::SaveMap save;
  save.request.path = path;
  ASSERT_TRUE(call("save_map", &save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  LandmarkMapFile file;
  ASSERT_EQ(readLandmarkMap(path, &file), "");
  ASSERT_EQ(file.landmarks.size(), saved.landmarks.size());
  for (size_t i = 0; i < file.landmarks.size(); ++i) {
    EXPECT_EQ(file.landmarks[i].id, saved.landmarks[i].id);
    EXPECT_EQ(file.landmarks[i].position.x(), saved.landmarks[i].x);
    EXPECT_EQ(file.landmarks[i].covariance(0, 1), saved.landmarks[i].covariance[1]);
  }
  addLines(&file);  // lines load too
  ASSERT_EQ(writeLandmarkMap(path, file), "");

  // A save to a directory is refused before any file is written: the grid
  // that would go beside it is not there either.
  char folder[] = "/tmp/slam_node_save_XXXXXX";
  ASSERT_NE(::mkdtemp(folder), nullptr);
  const std::string taken = std::string(folder) + "/map.yaml";
  ASSERT_EQ(::mkdir(taken.c_str(), 0755), 0);
  ekf_slam::SaveMap to_folder;
  to_folder.request.path = taken;
  ASSERT_TRUE(call("save_map", &to_folder));
  EXPECT_FALSE(to_folder.response.success);
  EXPECT_NE(to_folder.response.message.find(taken + ": is a directory"), std::string::npos)
      << to_folder.response.message;
  EXPECT_EQ(::rmdir(taken.c_str()), 0);
  EXPECT_EQ(::rmdir(folder), 0) << "the refused save wrote a file beside the directory";

  // Reset: an empty map.
  ASSERT_TRUE(trigger("reset"));
  EXPECT_TRUE(waitFor([&] { return observer_.map().landmarks.empty(); }, 3.0));
  ASSERT_TRUE(freshDiagnostics());
  EXPECT_EQ(observer_.diagnostic("landmarks"), 0.0);

  // A bad file is refused and changes nothing.
  ekf_slam::LoadMap bad;
  bad.request.path = "/nonexistent/map.yaml";
  ASSERT_TRUE(call("load_map", &bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("cannot open"), std::string::npos);
  EXPECT_TRUE(observer_.map().landmarks.empty());

  // Load: the same landmarks, bit for bit.
  ekf_slam::LoadMap load;
  load.request.path = path;
  load.request.localize_only = true;
  ASSERT_TRUE(call("load_map", &load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  EXPECT_EQ(load.response.landmarks, static_cast<int>(saved.landmarks.size()) + 2);
  EXPECT_TRUE(waitFor([&] { return sameLandmarks(observer_.map(), saved); }, 3.0))
      << observer_.map().landmarks.size() << " landmarks after load, saved "
      << saved.landmarks.size();
  expectAddedLines(observer_.map());
  std::remove(path);

  // Localisation only: iterations go on, the map never grows.
  ASSERT_TRUE(trigger("resume"));
  ASSERT_TRUE(freshDiagnostics());
  const double before_localising = observer_.diagnostic("iterations");
  EXPECT_TRUE(
      waitFor([&] { return observer_.diagnostic("iterations") > before_localising + 10; }, 5.0));
  EXPECT_LE(observer_.map().landmarks.size(), saved.landmarks.size());
  EXPECT_EQ(observer_.diagnosticText("localize only"), "True");

  expectSmoothedGrid();
}

// ~write_state and ~load_state: the whole state goes to a file and comes
// back with the map as it was; a file that is not a whole state, and a
// save to a directory, are refused with the map kept.
TEST_F(SlamNodeTest, WritesAndLoadsTheWholeState) {
  ASSERT_TRUE(trigger("resume"));
  ASSERT_TRUE(waitFor([&] { return observer_.map().landmarks.size() >= 3; }, 10.0));
  ASSERT_TRUE(trigger("pause"));
  ros::WallDuration(0.5).sleep();
  const ekf_slam::LandmarkMap saved = observer_.map();
  char folder[] = "/tmp/slam_node_state_XXXXXX";
  ASSERT_NE(::mkdtemp(folder), nullptr);
  const std::string path = std::string(folder) + "/office.state";

  ekf_slam::StateFile write;
  write.request.path = path;
  ASSERT_TRUE(call("write_state", &write));
  ASSERT_TRUE(write.response.success) << write.response.message;
  ekf_slam::SlamState state;
  ASSERT_EQ(ekf_slam::readSlamState(path, &state), "");
  // Every landmark, the tentative ones too (the published map leaves them out).
  EXPECT_GE(state.filter.landmarkCount(), static_cast<int>(saved.landmarks.size()));

  // What the node replies to a call it must refuse.
  auto refusal = [this](const std::string& service, const std::string& file) {
    ekf_slam::StateFile srv;
    srv.request.path = file;
    if (!call(service, &srv)) return "no reply from " + service;
    return srv.response.success ? "accepted: " + srv.response.message : srv.response.message;
  };
  const std::string to_folder = refusal("write_state", folder);
  EXPECT_NE(to_folder.find("is a directory"), std::string::npos) << to_folder;

  // A truncated state is refused; the running map stays.
  std::string bytes;
  ASSERT_TRUE(ekf_slam::readWholeFile(path, &bytes));
  const std::string broken = std::string(folder) + "/broken.state";
  ASSERT_EQ(ekf_slam::writeFileAtomically(broken, bytes.substr(0, bytes.size() - 100)), "");
  const std::string load_broken = refusal("load_state", broken);
  EXPECT_NE(load_broken.find("truncated"), std::string::npos) << load_broken;
  EXPECT_NE(load_broken.find("current map is kept"), std::string::npos) << load_broken;
  ros::WallDuration(0.3).sleep();
  EXPECT_TRUE(sameLandmarks(observer_.map(), saved));

  // After a reset, the saved state brings the map back bit for bit, and
  // mapping goes on from it.
  ASSERT_TRUE(trigger("reset"));
  EXPECT_TRUE(waitFor([&] { return observer_.map().landmarks.empty(); }, 3.0));
  ekf_slam::StateFile load;
  load.request.path = path;
  ASSERT_TRUE(call("load_state", &load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  EXPECT_TRUE(waitFor([&] { return sameLandmarks(observer_.map(), saved); }, 3.0))
      << observer_.map().landmarks.size() << " landmarks after load_state, saved "
      << saved.landmarks.size();
  ASSERT_TRUE(trigger("resume"));
  ASSERT_TRUE(freshDiagnostics());
  const double iterations = observer_.diagnostic("iterations");
  EXPECT_TRUE(waitFor([&] { return observer_.diagnostic("iterations") > iterations + 10; }, 5.0));
  EXPECT_GE(observer_.map().landmarks.size(), saved.landmarks.size());
  std::remove(path.c_str());
  std::remove(broken.c_str());
  ::rmdir(folder);
}

double headingOf(const geometry_msgs::Quaternion& q);

// The fraction of points along the middle of each wall of the room (room
// frame = odom) whose grid cell, or a neighbour, is occupied; `map_from_odom`
// places the room in the grid's frame. The lowest of the four.
double leastWallCoverage(const nav_msgs::OccupancyGrid& grid, const Pose2& map_from_odom) {
  const std::vector<std::pair<Vector2, Vector2>> walls = {{{-2.5, -3.0}, {2.5, -3.0}},
                                                          {{-2.5, 3.0}, {2.5, 3.0}},
                                                          {{-4.0, -1.5}, {-4.0, 1.5}},
                                                          {{4.0, -1.5}, {4.0, 1.5}}};
  const double resolution = grid.info.resolution;
  auto occupied = [&](const Vector2& p) {
    const int cx = static_cast<int>(std::floor((p.x() - grid.info.origin.position.x) / resolution));
    const int cy = static_cast<int>(std::floor((p.y() - grid.info.origin.position.y) / resolution));
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        const int x = cx + dx, y = cy + dy;
        if (x < 0 || y < 0 || x >= static_cast<int>(grid.info.width) ||
            y >= static_cast<int>(grid.info.height)) {
          continue;
        }
        if (grid.data[static_cast<size_t>(y) * grid.info.width + x] > 65) return true;
      }
    }
    return false;
  };
  double least = 1.0;
  for (const auto& [from, to] : walls) {
    const int samples = 50;
    int hits = 0;
    for (int i = 0; i < samples; ++i) {
      const Vector2 room = from + (to - from) * (i + 0.5) / samples;
      hits += occupied(transformFrom(map_from_odom, room));
    }
    least = std::min(least, static_cast<double>(hits) / samples);
  }
  return least;
}

// ~smooth with history_max_scans: 30 (test/slam_node_bounded_history.test,
// with and without loop closure). The node keeps at most 9/8 of it, and
// ~smooth, over those 3 s of the circle, still gives a grid with every wall
// of the room: the older scans reach it through the key scans at their
// loop-closed poses, or through the grid the node keeps of them.
TEST_F(SlamNodeTest, ABoundedHistoryStillSmoothsAndMapsTheWholeRoom) {
  // A whole turn of the circle (2π / turn_rate: 14 s at the launch file's
  // 0.45 rad/s) and a fifth more.
  const double whole_turn = 1.2 * 2.0 * kPi / Robot::turnRate() * kRate;
  ASSERT_TRUE(waitFor([&] { return observer_.diagnostic("scans processed") > whole_turn; }, 120.0))
      << observer_.diagnostic("scans processed") << " scans processed";
  ASSERT_TRUE(freshDiagnostics());
  const double kept = observer_.diagnostic("scans kept for smoothing");
  EXPECT_GE(kept, 30.0);
  EXPECT_LE(kept, 33.0);
  std_srvs::Trigger smooth;
  ASSERT_TRUE(call("smooth", &smooth));
  ASSERT_TRUE(smooth.response.success) << smooth.response.message;
  EXPECT_NE(smooth.response.message.find("history_max_scans"), std::string::npos)
      << smooth.response.message;
  EXPECT_TRUE(waitFor([&] { return observer_.smoothedPoses() >= 30; }, 3.0));
  ASSERT_TRUE(waitFor([&] { return observer_.grid().info.width > 0; }, 3.0));
  expectMetadataOfTheShownGrid();  // with loop closure off there is no live map
  // map → odom from the last published pose and the odometry at its stamp.
  const geometry_msgs::PoseWithCovarianceStamped pose = observer_.pose();
  const Pose2 map_pose(pose.pose.pose.position.x, pose.pose.pose.position.y,
                       headingOf(pose.pose.pose.orientation));
  const Pose2 map_from_odom = compose(map_pose, inverse(robot_.odometryAt(pose.header.stamp)));
  const double coverage = leastWallCoverage(observer_.grid(), map_from_odom);
  std::cout << "~smooth: " << smooth.response.message << "; least wall coverage " << coverage
            << "\n";
  EXPECT_GT(coverage, 0.6) << "a wall of the room is missing from the ~smooth grid";
}

bool sameGrid(const nav_msgs::OccupancyGrid& map, const GridMapFile& file) {
  return map.info.width == static_cast<uint32_t>(file.width) &&
         map.info.height == static_cast<uint32_t>(file.height) &&
         map.info.resolution == static_cast<float>(file.resolution) &&
         map.info.origin.position.x == file.origin_x &&
         map.info.origin.position.y == file.origin_y && map.data == file.cells;
}

double headingOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

// Localisation in a saved map: save_map writes the occupancy grid beside the
// landmarks and load_map publishes it again bit for bit; a robot loaded at a
// wrong pose (LoadMap's pose field) stays wrong until rviz's "2D Pose
// Estimate" (/initialpose) gives the right one, then tracks it.
TEST_F(SlamNodeTest, SavedGridReloadsAndInitialPoseRelocalises) {
  ASSERT_TRUE(trigger("reset"));
  trigger("resume");
  const long grids_before = observer_.grids();
  ASSERT_TRUE(waitFor([&] { return confirmedLandmarks(observer_.map()) >= 3; }, 30.0));
  ASSERT_TRUE(waitFor([&] { return observer_.grids() > grids_before; }, 30.0))
      << "no live occupancy grid on map";

  // map → odom as mapped (odometry is the truth here, so this holds).
  const geometry_msgs::PoseWithCovarianceStamped mapped = observer_.pose();
  const Pose2 map_to_odom = compose(Pose2(mapped.pose.pose.position.x, mapped.pose.pose.position.y,
                                          headingOf(mapped.pose.pose.orientation)),
                                    inverse(robot_.odometryAt(mapped.header.stamp)));
  auto truthAt = [&](const ros::Time& stamp) {
    return compose(map_to_odom, robot_.odometryAt(stamp));
  };

  // Save while paused, after any grid in the making has been published.
  char dir[] = "/tmp/slam_node_gridXXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/lab.yaml";
  GridMapFile file;
  ASSERT_NO_FATAL_FAILURE(saveShownGrid(path, std::string(dir) + "/lab_grid.yaml", &file));

  // Load at a pose 0.5 m off the truth, localisation only: the grid comes
  // back on map bit for bit, and the pose stays off.
  const long grids_at_load = observer_.grids();
  const ros::Time now = ros::Time::now();
  const Pose2 wrong = compose(truthAt(now), Pose2(0.5, 0.0, 0.0));
  ekf_slam::LoadMap load;
  load.request.path = path;
  load.request.localize_only = true;
  load.request.set_pose = true;
  load.request.pose.pose = poseMessage(wrong);
  ASSERT_TRUE(call("load_map", &load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  ASSERT_TRUE(waitFor([&] { return observer_.grids() > grids_at_load; }, 5.0));
  EXPECT_TRUE(sameGrid(observer_.grid(), file)) << "the loaded grid differs from the saved one";
  expectMetadataOfTheShownGrid();  // the loaded grid
  // dynamic_map answers with the grid on map.
  nav_msgs::GetMap get_map;
  ASSERT_TRUE(ros::service::call("/dynamic_map", get_map));
  EXPECT_TRUE(sameGrid(get_map.response.map, file)) << "dynamic_map differs from map";
  EXPECT_EQ(get_map.response.map.header.frame_id, "map");
  const ros::Time resumed = ros::Time::now();
  ASSERT_TRUE(trigger("resume"));
  // Poses of scans after the resume (a loaded machine may take a while).
  ASSERT_TRUE(
      waitFor([&] { return observer_.lastPoseStamp() > resumed + ros::Duration(1.0); }, 5.0));
  auto errorNow = [&](double* heading_error) {
    const geometry_msgs::PoseWithCovarianceStamped p = observer_.pose();
    const Pose2 truth = truthAt(p.header.stamp);
    *heading_error = std::abs(wrapAngle(headingOf(p.pose.pose.orientation) - truth.theta));
    return std::hypot(p.pose.pose.position.x - truth.x, p.pose.pose.position.y - truth.y);
  };
  double heading_error = 0.0;
  EXPECT_GT(errorNow(&heading_error), 0.3) << "a wrong start should stay wrong without help";
  // The grid loaded for localisation stays: the live map does not replace it.
  EXPECT_TRUE(sameGrid(observer_.grid(), file));

  // /initialpose with the truth (rviz gives about this covariance).
  ros::NodeHandle node;
  ros::Publisher initial_pose =
      node.advertise<geometry_msgs::PoseWithCovarianceStamped>("initialpose", 1, true);
  geometry_msgs::PoseWithCovarianceStamped estimate;
  estimate.header.frame_id = "map";
  estimate.header.stamp = ros::Time::now();
  estimate.pose.pose = poseMessage(truthAt(ros::Time::now()));
  estimate.pose.covariance[0] = estimate.pose.covariance[7] = 0.05 * 0.05;
  estimate.pose.covariance[35] = std::pow(degToRad(3.0), 2);
  initial_pose.publish(estimate);
  EXPECT_TRUE(
      waitFor([&] { return observer_.diagnostic("relocalisations (initialpose)") >= 1.0; }, 10.0));
  // Tracked since: poses of scans well after the estimate.
  ASSERT_TRUE(waitFor(
      [&] { return observer_.lastPoseStamp() > estimate.header.stamp + ros::Duration(2.0); }, 5.0));
  EXPECT_LT(errorNow(&heading_error), 0.05);
  EXPECT_LT(heading_error, degToRad(2.0));
  EXPECT_EQ(observer_.diagnosticText("localize only"), "True");

  // One in another frame is ignored, and says why.
  estimate.header.frame_id = "odom";
  initial_pose.publish(estimate);
  waitFor([&] { return observer_.hasLogged("initialpose in frame 'odom'", "ignored"); }, 2.0);
  EXPECT_TRUE(observer_.logged("initialpose in frame 'odom'", "ignored"));
  std::system(("rm -rf '" + std::string(dir) + "'").c_str());
}

// input: features (slam_node_features_input.test): ekf_slam_node maps from
// feature_node's messages; corrupt ones are refused, counted and named, and
// the map stays as it was; ~smooth has no scans for a grid and says so.
TEST_F(SlamNodeTest, FeaturesInputMapsAndRefusesCorruptFeatures) {
  ros::NodeHandle node;
  ros::Publisher features_out = node.advertise<ekf_slam::Features>("features", 10);
  ASSERT_TRUE(waitFor([&] { return features_out.getNumSubscribers() > 0; }, 5.0))
      << "ekf_slam_node does not subscribe to features (input: features)";
  // Mapping from features alone: the map is growing (SetUp saw >= 3 landmarks).
  ASSERT_TRUE(freshDiagnostics());
  const double iterations_start = observer_.diagnostic("iterations");
  EXPECT_TRUE(waitFor([&] { return observer_.diagnostic("iterations") > iterations_start; }, 5.0));

  robot_.publish_scans = false;  // feature_node falls silent too
  ros::WallDuration(1.0).sleep();
  ASSERT_TRUE(freshDiagnostics());
  const ekf_slam::LandmarkMap before = observer_.map();
  const long maps_before = observer_.maps();
  const double bad_before = observer_.diagnostic("dropped: bad features");
  const double iterations_before = observer_.diagnostic("iterations");
  ASSERT_FALSE(std::isnan(bad_before));

  ekf_slam::Features good = observer_.features();
  int candidate = -1;
  for (size_t i = 0; i < good.points.size(); ++i) {
    if (good.points[i].landmark_candidate) candidate = static_cast<int>(i);
  }
  ASSERT_GE(candidate, 0) << "feature_node's last message has no landmark candidate";
  // 1. A NaN in a candidate's covariance; 2. an unknown point kind. Both
  // fresh stamps, so only their content can be refused.
  ekf_slam::Features nan_covariance = good;
  nan_covariance.header.stamp = ros::Time::now();
  nan_covariance.points[candidate].range_bearing_covariance[3] =
      std::numeric_limits<double>::quiet_NaN();
  features_out.publish(nan_covariance);
  ros::WallDuration(2.2).sleep();  // past the node's per-reason log throttle (2 s)
  ekf_slam::Features unknown_kind = good;
  unknown_kind.header.stamp = ros::Time::now();
  unknown_kind.points[candidate].kind = "blob";
  features_out.publish(unknown_kind);
  ros::WallDuration(1.0).sleep();

  ASSERT_TRUE(freshDiagnostics());
  EXPECT_EQ(observer_.diagnostic("dropped: bad features"), bad_before + 2);
  EXPECT_EQ(observer_.diagnostic("iterations"), iterations_before);
  EXPECT_TRUE(observer_.logged("bad features", "covariance is not finite"));
  EXPECT_TRUE(observer_.logged("bad features", "unknown kind 'blob'"));
  EXPECT_EQ(observer_.maps(), maps_before);
  EXPECT_TRUE(sameLandmarks(observer_.map(), before));

  robot_.publish_scans = true;
  EXPECT_TRUE(waitFor([&] { return observer_.diagnostic("iterations") > iterations_before; }, 5.0));
  EXPECT_GT(observer_.maps(), maps_before);

  std_srvs::Trigger smooth;
  ASSERT_TRUE(call("smooth", &smooth));
  EXPECT_TRUE(smooth.response.success) << smooth.response.message;
  EXPECT_NE(smooth.response.message.find("no occupancy grid"), std::string::npos)
      << smooth.response.message;
  EXPECT_TRUE(waitFor([&] { return observer_.smoothedPoses() > 10; }, 3.0));
}

}  // namespace
}  // namespace ekf_slam

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "slam_node_rostest");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
