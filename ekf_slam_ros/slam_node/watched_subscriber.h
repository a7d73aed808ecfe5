// A subscription whose queue is sized and watched. roscpp's own queue
// discards the oldest message silently when the node falls behind. Here a
// thread of this class takes each message from roscpp at once (that queue,
// 10,000 long, does not fill: the thread only files each message) and keeps
// at most `capacity` of them for the node's callback thread; when the node is that far behind, the
// oldest waiting message is discarded and reported, on the node's thread, before the next one is
// delivered.
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <algorithm>
#include <atomic>
#include <boost/make_shared.hpp>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace ekf_slam {

template <class M>
class WatchedSubscriber {
 public:
  using Callback = std::function<void(const typename M::ConstPtr&)>;
  // The node's callback queue runs `callback` for each message in arrival
  // order, and `discarded(n)` first when n messages were discarded since.
  WatchedSubscriber(ros::NodeHandle node, const std::string& topic, size_t capacity,
                    Callback callback, std::function<void(long)> discarded)
      : capacity_(capacity),
        callback_(std::move(callback)),
        discarded_(std::move(discarded)),
        target_(node.getCallbackQueue()) {
    ros::NodeHandle intake(node);
    intake.setCallbackQueue(&intake_queue_);
    subscriber_ = intake.subscribe<M>(
        topic, static_cast<uint32_t>(std::max<size_t>(capacity, 10000)),
        [this](const typename M::ConstPtr& message) { onMessage(message); }, ros::VoidConstPtr(),
        ros::TransportHints().tcpNoDelay());
    thread_ = std::thread([this] {
      while (running_ && ros::ok()) intake_queue_.callAvailable(ros::WallDuration(0.01));
    });
  }

  ~WatchedSubscriber() {
    subscriber_.shutdown();
    running_ = false;
    if (thread_.joinable()) thread_.join();
    target_->removeByID(ownerId());
  }

  WatchedSubscriber(const WatchedSubscriber&) = delete;
  WatchedSubscriber& operator=(const WatchedSubscriber&) = delete;

  std::string topic() const { return subscriber_.getTopic(); }

 private:
  class Delivery : public ros::CallbackInterface {
   public:
    explicit Delivery(WatchedSubscriber* owner) : owner_(owner) {}
    CallResult call() override {
      owner_->deliverNext();
      return Success;
    }

   private:
    WatchedSubscriber* owner_;
  };

  uint64_t ownerId() const { return static_cast<uint64_t>(reinterpret_cast<uintptr_t>(this)); }

  // The intake thread: keep the message, hand a delivery to the node's queue.
  void onMessage(const typename M::ConstPtr& message) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (waiting_.size() >= capacity_) {
        waiting_.pop_front();
        ++discarded_since_;
      }
      waiting_.push_back(message);
    }
    target_->addCallback(boost::make_shared<Delivery>(this), ownerId());
  }

  // The node's thread. One delivery per message: those of discarded
  // messages find the queue empty and only report.
  void deliverNext() {
    typename M::ConstPtr message;
    long discarded = 0;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      discarded = discarded_since_;
      discarded_since_ = 0;
      if (!waiting_.empty()) {
        message = waiting_.front();
        waiting_.pop_front();
      }
    }
    if (discarded > 0) discarded_(discarded);
    if (message) callback_(message);
  }

  const size_t capacity_;
  Callback callback_;
  std::function<void(long)> discarded_;
  ros::CallbackQueueInterface* target_;
  ros::CallbackQueue intake_queue_;
  ros::Subscriber subscriber_;
  std::atomic<bool> running_{true};
  std::thread thread_;
  std::mutex mutex_;
  std::deque<typename M::ConstPtr> waiting_;
  long discarded_since_ = 0;
};

}  // namespace ekf_slam
