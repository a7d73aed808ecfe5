// The loop-closing back end as the pipeline drives it: a LoopCloser fed
// with every scan, either inline (each scan waits for the search and the
// optimisation it triggers) or on its own thread (scan processing goes on
// while the back end searches and optimises).
//
// The caller reads the back end through views: what the graph held after a
// given number of scans had been processed (key-scan poses, their front-end
// poses, stamps, points, counters). When a correction takes effect is fixed
// by `correction_delay` (LoopClosureOptions), in scans:
//   - d >= 0 (deterministic): scan n is given the view after scans
//     0 … n − d were processed. On its own thread the back end may run up
//     to d scans behind; scan n waits only when it is further behind. Inline
//     and threaded runs give bit-identical views, so a live node and the
//     offline runner publish the same poses. d = 0 is the synchronous
//     back end.
//   - d = −1 (as soon as ready): on its own thread, scan n is given the
//     newest view, whatever the back end has processed; nothing ever
//     waits. Inline this is d = 0.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "ekf_slam_core/loop_closure/loop_closer.h"

namespace ekf_slam {

// A loop of the graph between two key scans (for drawing it).
struct LoopLink {
  int from = 0, to = 0;
  bool heading_only = false;  // a heading edge between the walls of one place
};

// The back end's state after `scans` scans had been processed.
struct BackEndView {
  long scans = 0;
  LoopClosureCounters counters;
  std::vector<Pose2> key_poses;      // graph pose of each key scan (graph frame)
  std::vector<Pose2> key_front_end;  // front-end pose of each key scan
  std::vector<double> key_stamps;
  std::vector<int> key_scan_index;  // index of the key scan's scan in addScan order
  std::vector<std::shared_ptr<const std::vector<Vector2>>> key_points;  // robot frame
  std::vector<LoopLink> loops;  // the graph's active loop and heading edges

  // The loop-closed pose (graph frame) of a scan whose front-end pose is
  // `front_end`: hung off the newest key scan of the view. Before the first
  // key scan: the front end's pose.
  Pose2 poseOf(const Pose2& front_end) const;
  // The newest key scan taken at or before scan `scan_index` (−1: none).
  int keyAtOrBefore(int scan_index) const;
};

class LoopClosureBackEnd {
 public:
  // `own_thread`: run the LoopCloser on a thread of its own;
  // `scan_history`: the LoopCloser's bound on its per-scan entries.
  LoopClosureBackEnd(const LoopClosureOptions& options, const ScanMatcherOptions& matcher,
                     bool own_thread, long scan_history = 0);
  ~LoopClosureBackEnd();
  // A snapshot: waits until `other` has processed every scan handed over,
  // then copies its LoopCloser and views; the copy runs a thread of its own
  // when `other` does, and continues as `other` would. Not while another
  // thread hands `other` scans.
  LoopClosureBackEnd(const LoopClosureBackEnd& other);
  LoopClosureBackEnd& operator=(const LoopClosureBackEnd&) = delete;

  // Every scan, in order (see LoopCloser::addScan). Returns the view this
  // scan is given (see the correction delay above).
  std::shared_ptr<const BackEndView> addScan(double stamp, const Scan& scan,
                                             const Pose2& laser_pose, const Pose2& front_end,
                                             bool usable);

  // Scans handed over that the back end has not processed yet.
  long backlog() const;

  // Continues from a saved closer (LoopCloser::resume), once the scans
  // handed so far are processed: the next scan is state.scan_count. Empty
  // on success, else what is inconsistent in `state`.
  std::string resume(const LoopCloserState& state);
  // The view of everything processed so far.
  std::shared_ptr<const BackEndView> newestView() const;

  // Waits until every scan handed over has been processed, then gives the
  // LoopCloser itself. Its use must end before the next addScan.
  LoopCloser& drained();
  const LoopCloser& drained() const { return const_cast<LoopClosureBackEnd*>(this)->drained(); }

 private:
  struct Input {
    double stamp;
    Scan scan;
    Pose2 laser_pose;
    Pose2 front_end;
    bool usable;
  };
  void run();
  // After the closer processed a scan (lock held): a new view when the
  // graph changed, else the scan count moves on.
  void publish();

  const int delay_;  // correction_delay
  const bool own_thread_;
  LoopCloser closer_;
  mutable std::mutex mutex_;      // guards what follows, and closer_ while the worker uses it
  long handed_ = 0;               // scans given to addScan
  std::condition_variable work_;  // inputs waiting, or stop
  std::condition_variable done_;  // a scan processed
  std::deque<Input> inputs_;
  bool stop_ = false;
  bool busy_ = false;    // the worker is processing a scan
  long processed_ = 0;   // scans the closer has processed
  long key_count_ = -1;  // of the newest view …
  long optimisations_ = -1;
  // Views by the scan count they hold after, oldest first: the newest, and
  // those a deterministic caller may still ask for.
  std::deque<std::shared_ptr<const BackEndView>> views_;
  std::thread worker_;
};

}  // namespace ekf_slam
