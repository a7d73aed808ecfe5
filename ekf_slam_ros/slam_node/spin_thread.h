// Work a handler on another thread hands to the spin thread. ekf_slam_node
// keeps the SLAM state on one thread, the one that spins the global
// callback queue (it takes the scans and publishes tf). The slow services
// (~smooth, ~save_map, ~load_map) run on a thread of their own, so that a
// long solve or a large file never holds up map → odom; what they read or
// change of the state they hand to the spin thread through this, to run
// between two of its callbacks.
#pragma once

#include <atomic>
#include <functional>

namespace ekf_slam {

// Runs `work` on the spin thread and waits for it; an exception it throws
// is rethrown here. False, with `work` not run, when the node shuts down
// (`closing` set, or ros::ok() false) before the spin thread got to it.
// Never call it from the spin thread itself: it would wait for itself.
bool runOnSpinThread(const std::function<void()>& work, const std::atomic<bool>& closing);

}  // namespace ekf_slam
