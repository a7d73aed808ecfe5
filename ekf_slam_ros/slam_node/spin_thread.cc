#include "ekf_slam_ros/slam_node/spin_thread.h"

#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <boost/make_shared.hpp>
#include <chrono>
#include <cstdint>
#include <exception>
#include <future>
#include <memory>

namespace ekf_slam {
namespace {

class WorkCallback : public ros::CallbackInterface {
 public:
  WorkCallback(const std::function<void()>& work, std::shared_ptr<std::promise<void>> done)
      : work_(work), done_(std::move(done)) {}

  CallResult call() override {
    try {
      work_();
      done_->set_value();
    } catch (...) {
      done_->set_exception(std::current_exception());
    }
    return Success;
  }

 private:
  std::function<void()> work_;
  std::shared_ptr<std::promise<void>> done_;
};

}  // namespace

bool runOnSpinThread(const std::function<void()>& work, const std::atomic<bool>& closing) {
  auto done = std::make_shared<std::promise<void>>();
  std::future<void> finished = done->get_future();
  // The promise's address names this call in the queue while it lives, so
  // that a call given up on can be taken out again.
  const auto owner = static_cast<uint64_t>(reinterpret_cast<uintptr_t>(done.get()));
  ros::CallbackQueue& queue = *ros::getGlobalCallbackQueue();
  queue.addCallback(boost::make_shared<WorkCallback>(work, done), owner);
  while (finished.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
    if (closing || !ros::ok()) {
      // Waits for a call in progress; afterwards the work cannot start.
      queue.removeByID(owner);
      if (finished.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return false;
      break;
    }
  }
  finished.get();
  return true;
}

}  // namespace ekf_slam
