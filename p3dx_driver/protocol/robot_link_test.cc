// RobotLink (the driver's side) against P3dxEmulator (the robot's side) over
// a real pseudo-terminal, without ROS.
#include "p3dx_driver/protocol/robot_link.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <mutex>
#include <thread>

#include "p3dx_driver/emulator/p3dx_emulator.h"
#include "serial_io/pseudo_terminal.h"

namespace p3dx {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

std::string uniqueLink(const std::string& tag) {
  return "/tmp/p3dx_link_test_" + tag + "_" + std::to_string(::getpid());
}

// Runs the emulator on its own thread, stepping every 2 ms.
class EmulatorThread {
 public:
  EmulatorThread(const std::string& link, EmulatorOptions options) {
    EXPECT_TRUE(pty_.open(link)) << pty_.error();
    robot_ = std::make_unique<P3dxEmulator>(&pty_, options);
    thread_ = std::thread([this] {
      const Clock::time_point start = Clock::now();
      while (!stop_) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          robot_->step(std::chrono::duration<double>(Clock::now() - start).count());
        }
        std::this_thread::sleep_for(milliseconds(2));
      }
    });
  }
  ~EmulatorThread() {
    stop_ = true;
    thread_.join();
  }
  template <typename F>
  auto with(F f) {
    std::lock_guard<std::mutex> lock(mutex_);
    return f(*robot_, pty_);
  }

 private:
  serial_io::PseudoTerminal pty_;
  std::unique_ptr<P3dxEmulator> robot_;
  std::mutex mutex_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Spins the link until `done(last sample)` or the timeout; returns the
// samples received.
std::vector<OdometrySample> spinUntil(RobotLink* link, double seconds,
                                      const std::function<bool(const RobotLink&)>& done) {
  std::vector<OdometrySample> samples;
  const Clock::time_point deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                        std::chrono::duration<double>(seconds));
  while (Clock::now() < deadline) {
    link->spinOnce(milliseconds(10), &samples);
    if (done(*link)) break;
  }
  return samples;
}

std::vector<OdometrySample> spinFor(RobotLink* link, double seconds) {
  return spinUntil(link, seconds, [](const RobotLink&) { return false; });
}

bool connected(const RobotLink& link) { return link.state() == LinkState::kConnected; }

LinkOptions optionsFor(const std::string& link) {
  LinkOptions options;
  options.port = link;
  options.linear_acceleration = options.linear_deceleration = 1.0;
  return options;
}

TEST(RobotLink, HandshakeReadsIdentityAndUsesTheSubclassFactors) {
  const std::string path = uniqueLink("hs");
  EmulatorOptions emulator;
  emulator.name = "robbie";
  emulator.subclass = "p3dx-sh";
  EmulatorThread robot(path, emulator);
  RobotLink link(optionsFor(path));
  spinUntil(&link, 5.0, connected);
  ASSERT_TRUE(connected(link)) << link.lastError();
  EXPECT_EQ(link.identity().name, "robbie");
  EXPECT_EQ(link.identity().robot_class, "Pioneer");
  EXPECT_EQ(link.identity().subclass, "p3dx-sh");
  EXPECT_DOUBLE_EQ(link.conversions().distance_mm_per_tick, 1.0);
  spinFor(&link, 0.5);
  EXPECT_TRUE(robot.with([](P3dxEmulator& r, auto&) { return r.motorsEnabled(); }));
}

TEST(RobotLink, ProbesBaudRatesAndClosesAStaleSession) {
  const std::string path = uniqueLink("baud");
  EmulatorOptions emulator;
  emulator.baud = 38400;
  emulator.stale_session = true;
  EmulatorThread robot(path, emulator);
  RobotLink link(optionsFor(path));
  spinUntil(&link, 8.0, connected);
  ASSERT_TRUE(connected(link)) << link.lastError();
  EXPECT_EQ(link.connectedBaud(), 38400);
  link.shutdown();
  EXPECT_GE(link.stats().stale_sessions_closed, 1u);
}

TEST(RobotLink, OdometryMatchesTheRobotAfterDriving) {
  const std::string path = uniqueLink("drive");
  EmulatorThread robot(path, EmulatorOptions{});
  RobotLink link(optionsFor(path));
  spinUntil(&link, 5.0, connected);
  ASSERT_TRUE(connected(link)) << link.lastError();
  std::vector<OdometrySample> samples;
  const Clock::time_point end = Clock::now() + milliseconds(1500);
  while (Clock::now() < end) {
    link.setVelocity(0.4, 0.5, Clock::now());
    link.spinOnce(milliseconds(10), &samples);
  }
  link.setVelocity(0.0, 0.0, Clock::now());
  auto rest = spinFor(&link, 1.5);
  ASSERT_FALSE(rest.empty());
  const ekf_slam::Pose2 truth = robot.with([](P3dxEmulator& r, auto&) { return r.odometryPose(); });
  EXPECT_GT(std::hypot(truth.x, truth.y), 0.2);
  EXPECT_LT(ekf_slam::maxAbsDifference(rest.back().pose, truth), 2e-3);
}

TEST(RobotLink, CmdVelTimeoutStopsTheRobotBeforeTheWatchdog) {
  const std::string path = uniqueLink("timeout");
  EmulatorThread robot(path, EmulatorOptions{});
  LinkOptions options = optionsFor(path);
  options.cmd_vel_timeout = 0.3;
  RobotLink link(options);
  spinUntil(&link, 5.0, connected);
  ASSERT_TRUE(connected(link));
  link.setVelocity(0.3, 0.0, Clock::now());
  spinFor(&link, 0.2);
  EXPECT_GT(robot.with([](P3dxEmulator& r, auto&) { return r.targetVelocity(); }), 0.29);
  spinFor(&link, 0.6);  // no further cmd_vel: timed out after 0.3 s
  EXPECT_EQ(robot.with([](P3dxEmulator& r, auto&) { return r.targetVelocity(); }), 0.0);
  EXPECT_EQ(robot.with([](P3dxEmulator& r, auto&) { return r.stats().watchdog_trips; }), 0u);
}

TEST(RobotLink, CorruptPacketsAreCountedAndSkippedWithoutJumps) {
  const std::string path = uniqueLink("corrupt");
  EmulatorOptions emulator;
  emulator.faults.corrupt_rate = 0.05;
  emulator.faults.garbage_rate = 0.05;
  emulator.faults.drop_rate = 0.02;
  EmulatorThread robot(path, emulator);
  RobotLink link(optionsFor(path));
  spinUntil(&link, 5.0, connected);
  ASSERT_TRUE(connected(link));
  std::vector<OdometrySample> samples;
  const Clock::time_point end = Clock::now() + milliseconds(4000);
  while (Clock::now() < end) {
    link.setVelocity(0.5, 0.3, Clock::now());
    link.spinOnce(milliseconds(10), &samples);
  }
  ASSERT_GT(samples.size(), 20u);
  EXPECT_GT(link.stats().checksum_errors, 0u);
  for (size_t i = 1; i < samples.size(); ++i) {
    const double dt =
        std::chrono::duration<double>(samples[i].arrival - samples[i - 1].arrival).count();
    const double step = std::hypot(samples[i].pose.x - samples[i - 1].pose.x,
                                   samples[i].pose.y - samples[i - 1].pose.y);
    EXPECT_LT(step, 0.5 * dt + 0.06) << "jump at sample " << i;  // 0.5 m/s + one lost SIP
  }
}

TEST(RobotLink, ReconnectsAfterUnplugAndChainsOdometry) {
  const std::string path = uniqueLink("unplug");
  EmulatorThread robot(path, EmulatorOptions{});
  RobotLink link(optionsFor(path));
  spinUntil(&link, 5.0, connected);
  ASSERT_TRUE(connected(link));
  std::vector<OdometrySample> samples;
  const Clock::time_point end = Clock::now() + milliseconds(1000);
  while (Clock::now() < end) {
    link.setVelocity(0.3, 0.0, Clock::now());
    link.spinOnce(milliseconds(10), &samples);
  }
  link.setVelocity(0.0, 0.0, Clock::now());
  auto before = spinFor(&link, 1.0);
  ASSERT_FALSE(before.empty());
  const ekf_slam::Pose2 last = before.back().pose;
  EXPECT_GT(last.x, 0.1);

  robot.with([](P3dxEmulator& r, serial_io::PseudoTerminal& pty) {
    pty.unplug();
    r.dropConnection();
    return 0;
  });
  spinUntil(&link, 3.0, [](const RobotLink& l) { return !connected(l); });
  EXPECT_FALSE(connected(link));
  EXPECT_FALSE(link.lastError().empty());
  robot.with([](P3dxEmulator&, serial_io::PseudoTerminal& pty) { return pty.replug(); });
  const Clock::time_point replugged = Clock::now();
  spinUntil(&link, 5.0, connected);
  ASSERT_TRUE(connected(link)) << link.lastError();
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - replugged).count(), 3.0);
  auto after = spinFor(&link, 0.5);
  ASSERT_FALSE(after.empty());
  // The robot's counters restarted at zero; the published pose did not.
  EXPECT_LT(ekf_slam::maxAbsDifference(after.back().pose, last), 2e-3);
  EXPECT_EQ(link.stats().connects, 2u);
}

TEST(RobotLink, RejectsNonFiniteCommandsAndReportsAMissingPort) {
  LinkOptions options = optionsFor("/tmp/p3dx_link_test_does_not_exist");
  RobotLink link(options);
  EXPECT_FALSE(link.setVelocity(std::nan(""), 0.0, Clock::now()));
  EXPECT_EQ(link.stats().rejected_commands, 1u);
  spinFor(&link, 0.1);
  EXPECT_FALSE(connected(link));
  EXPECT_NE(link.lastError().find("does_not_exist"), std::string::npos) << link.lastError();
}

}  // namespace
}  // namespace p3dx
