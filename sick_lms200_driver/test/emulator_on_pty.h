// Test helper: an Lms200Emulator on a real pseudo-terminal, stepped by a
// background thread on the wall clock, recording the truth of every scan it
// sends. Clients open device() with serial_io::SerialPort.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "serial_io/pseudo_terminal.h"
#include "sick_lms200_driver/emulator/lms200_emulator.h"
#include "sick_lms200_driver/emulator/room.h"

namespace sick_lms200 {
namespace test {

inline double wallNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

class EmulatorOnPty {
 public:
  EmulatorOnPty(EmulatorOptions options, const std::string& link) : world_(makeDemoRoom()) {
    EXPECT_TRUE(pty_.open(link)) << pty_.error();
    emulator_ = std::make_unique<Lms200Emulator>(
        pty_, world_, [](double) { return demoSensorPose(); }, options);
    emulator_->setPeerBaudSource([this] { return pty_.peerBaud(); });
    // Called inside spinOnce, which the thread below runs under mutex_.
    emulator_->setScanObserver([this](const TrueScan& truth) { truths_.push_back(truth); });
    thread_ = std::thread([this] {
      while (running_) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          emulator_->spinOnce(wallNow());
        }
        std::this_thread::sleep_for(std::chrono::microseconds(300));
      }
    });
  }
  ~EmulatorOnPty() {
    running_ = false;
    thread_.join();
  }
  EmulatorOnPty(const EmulatorOnPty&) = delete;
  EmulatorOnPty& operator=(const EmulatorOnPty&) = delete;

  // Runs f(emulator, truths) with the emulator's thread held.
  template <typename F>
  auto locked(F f) {
    std::lock_guard<std::mutex> lock(mutex_);
    return f(*emulator_, truths_);
  }
  std::string device() const { return pty_.devicePath(); }
  // Puts bytes on the line as if the sensor had sent them.
  void sendAsSensor(const std::vector<uint8_t>& bytes) {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(pty_.write(bytes.data(), bytes.size()), serial_io::IoStatus::kOk);
  }

 private:
  ekf_slam::sim::PolygonWorld world_;
  serial_io::PseudoTerminal pty_;
  std::unique_ptr<Lms200Emulator> emulator_;
  std::vector<TrueScan> truths_;
  std::mutex mutex_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

}  // namespace test
}  // namespace sick_lms200
