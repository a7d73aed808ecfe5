#include "ekf_slam_core/loop_closure/back_end.h"

#include <algorithm>
#include <string>
#include <utility>

namespace ekf_slam {
namespace {

// Scans the caller may hand over ahead of the back end in the
// as-soon-as-ready mode before it waits (a bound on the memory of a back
// end that cannot keep up at all, not a pacing: a loop search lasts a few
// scans).
constexpr long kMaxBacklog = 2000;

}  // namespace

Pose2 BackEndView::poseOf(const Pose2& front_end) const {
  if (key_poses.empty()) return front_end;
  const size_t k = key_poses.size() - 1;
  return compose(key_poses[k], between(key_front_end[k], front_end));
}

int BackEndView::keyAtOrBefore(int scan_index) const {
  const auto after = std::upper_bound(key_scan_index.begin(), key_scan_index.end(), scan_index);
  return static_cast<int>(after - key_scan_index.begin()) - 1;
}

LoopClosureBackEnd::LoopClosureBackEnd(const LoopClosureOptions& options,
                                       const ScanMatcherOptions& matcher, bool own_thread,
                                       long scan_history)
    : delay_(options.correction_delay),
      own_thread_(own_thread),
      closer_(options, matcher, scan_history) {
  views_.push_back(std::make_shared<const BackEndView>());
  key_count_ = 0;
  optimisations_ = 0;
  if (own_thread_) worker_ = std::thread([this] { run(); });
}

LoopClosureBackEnd::LoopClosureBackEnd(const LoopClosureBackEnd& other)
    : delay_(other.delay_), own_thread_(other.own_thread_), closer_(other.drained()) {
  {
    std::lock_guard<std::mutex> lock(other.mutex_);
    handed_ = other.handed_;
    processed_ = other.processed_;
    key_count_ = other.key_count_;
    optimisations_ = other.optimisations_;
    views_ = other.views_;  // immutable, shared
  }
  if (own_thread_) worker_ = std::thread([this] { run(); });
}

LoopClosureBackEnd::~LoopClosureBackEnd() {
  if (!own_thread_) return;
  {
    // Scans still waiting are dropped: whoever destroys the back end (a
    // reset, the node shutting down) has no use for their results.
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    inputs_.clear();
  }
  work_.notify_all();
  worker_.join();
}

void LoopClosureBackEnd::publish() {
  ++processed_;
  const LoopClosureCounters& counters = closer_.counters();
  // The graph and the counters change only when a key scan is added (its
  // loop search) or the graph is optimised.
  if (closer_.keyCount() == key_count_ && counters.optimisations == optimisations_) {
    return;  // the newest view still holds
  }
  auto view = std::make_shared<BackEndView>();
  view->scans = processed_;
  view->counters = counters;
  const int keys = closer_.keyCount();
  view->key_poses.reserve(keys);
  view->key_front_end.reserve(keys);
  view->key_stamps.reserve(keys);
  view->key_scan_index.reserve(keys);
  view->key_points.reserve(keys);
  for (int k = 0; k < keys; ++k) {
    view->key_poses.push_back(closer_.graph().pose(k));
    view->key_front_end.push_back(closer_.keyFrontEnd(k));
    view->key_stamps.push_back(closer_.keyStamp(k));
    view->key_scan_index.push_back(closer_.keyScanIndex(k));
    view->key_points.push_back(closer_.sharedKeyPoints(k));
  }
  const std::vector<PoseGraphEdge>& edges = closer_.graph().edges();
  for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
    if (edges[e].robust && edges[e].active) {
      view->loops.push_back({edges[e].from, edges[e].to, closer_.isHeadingEdge(e)});
    }
  }
  key_count_ = keys;
  optimisations_ = counters.optimisations;
  views_.push_back(std::move(view));
  // Only the deterministic mode asks for older views, never for one older
  // than the scan the caller is at minus the delay.
  if (delay_ < 0 || !own_thread_) {
    while (views_.size() > 1 && views_[1]->scans <= handed_ - std::max(delay_, 0)) {
      views_.pop_front();
    }
  }
}

std::shared_ptr<const BackEndView> LoopClosureBackEnd::addScan(double stamp, const Scan& scan,
                                                               const Pose2& laser_pose,
                                                               const Pose2& front_end,
                                                               bool usable) {
  std::unique_lock<std::mutex> lock(mutex_);
  ++handed_;
  if (!own_thread_) {
    closer_.addScan(stamp, scan, laser_pose, front_end, usable);
    publish();
  } else {
    done_.wait(lock, [this] { return handed_ - 1 - processed_ < kMaxBacklog; });
    inputs_.push_back(Input{stamp, scan, laser_pose, front_end, usable});
    work_.notify_one();
    if (delay_ < 0) return views_.back();
  }
  // Deterministic: the view after scans 0 … n − d (n = handed_ − 1), that
  // is after handed_ − d scans.
  const long target = std::max(0L, handed_ - std::max(delay_, 0));
  done_.wait(lock, [this, target] { return processed_ >= target; });
  while (views_.size() > 1 && views_[1]->scans <= target) views_.pop_front();
  return views_.front();
}

std::string LoopClosureBackEnd::resume(const LoopCloserState& state) {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return inputs_.empty() && !busy_; });
  const std::string error = closer_.resume(state);
  if (!error.empty()) return error;
  // The restored scans count as handed and processed; publish() counts the
  // last of them and makes the view of the restored graph.
  handed_ = state.scan_count;
  processed_ = state.scan_count - 1;
  key_count_ = -1;
  views_.clear();
  publish();
  return "";
}

std::shared_ptr<const BackEndView> LoopClosureBackEnd::newestView() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return views_.back();
}

long LoopClosureBackEnd::backlog() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return handed_ - processed_;
}

LoopCloser& LoopClosureBackEnd::drained() {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return inputs_.empty() && !busy_; });
  return closer_;
}

void LoopClosureBackEnd::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    work_.wait(lock, [this] { return stop_ || !inputs_.empty(); });
    if (stop_) return;
    Input input = std::move(inputs_.front());
    inputs_.pop_front();
    busy_ = true;
    lock.unlock();
    closer_.addScan(input.stamp, input.scan, input.laser_pose, input.front_end, input.usable);
    lock.lock();
    busy_ = false;
    publish();
    done_.notify_all();
  }
}

}  // namespace ekf_slam
