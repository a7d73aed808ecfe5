#include "ekf_slam_core/pipeline/back_end_link.h"

#include <algorithm>
#include <iterator>

namespace ekf_slam {

namespace {
std::unique_ptr<LoopClosureBackEnd> backEndFor(const PipelineOptions& options) {
  if (!options.loop_closure.enabled) return nullptr;
  // The loop closer keeps its per-scan entries for at least the history's
  // longest extent (history_scans plus the trimming step).
  const long history = options.history_scans > 0
                           ? options.history_scans + std::max(1L, options.history_scans / 8)
                           : 0;
  return std::make_unique<LoopClosureBackEnd>(options.loop_closure, options.scan_matching,
                                              options.back_end_thread, history);
}
}  // namespace

BackEndLink::BackEndLink(const PipelineOptions& options)
    : laser_pose_(options.filter.laser_pose), back_end_(backEndFor(options)) {}

BackEndLink::Step BackEndLink::addScan(double stamp, const Scan& scan, const Pose2& new_odometry,
                                       bool usable, const Pose2& filtered, long record,
                                       const std::vector<int>& observed, const EkfSlam& filter) {
  if (resume_at_) {
    front_end_offset_ = compose(*resume_at_, inverse(new_odometry));
    resume_at_.reset();
  }
  const Pose2 odometry =
      front_end_offset_ ? compose(*front_end_offset_, new_odometry) : new_odometry;
  last_front_end_ = odometry;
  const int loop_scan = first_loop_scan_ + static_cast<int>(record_of_loop_scan_.size());
  record_of_loop_scan_.push_back(record);
  pending_filtered_.push_back(filtered);
  for (int id : observed) {
    landmark_scan_[id] = loop_scan;
    const int slot = filter.slotOf(id);
    if (slot >= 0 && filter.landmarkKind(slot) == LandmarkKind::kPoint) {
      point_seen_at_[id] = filter.landmarkPosition(slot);
    }
  }
  view_ = back_end_->addScan(stamp, scan, laser_pose_, odometry, usable);
  const Pose2 graph_pose = view_->poseOf(odometry);
  if (!map_from_graph_) map_from_graph_ = compose(filtered, inverse(graph_pose));
  Step step;
  step.causal = compose(*map_from_graph_, graph_pose);
  trackKeyScans();
  step.new_loops = view_->counters.accepted != loops_seen_;
  loops_seen_ = view_->counters.accepted;
  return step;
}

// The filter's pose at each key scan the back end reports (its pose when
// that scan was processed, before any re-anchoring at it), so that a loop
// closure can move each landmark with the key scan it hangs off (the newest
// key scan at or before the scan that last observed it). The back end may report
// a key scan scans after it was taken: the poses wait in pending_filtered_.
void BackEndLink::trackKeyScans() {
  const BackEndView& view = *view_;
  while (key_filtered_.size() < view.key_poses.size()) {
    const long scan = view.key_scan_index[key_filtered_.size()];
    key_filtered_.push_back(pending_filtered_[scan - pending_base_]);
  }
  // Every key scan before the view's scans is known now.
  while (pending_base_ < view.scans && !pending_filtered_.empty()) {
    pending_filtered_.pop_front();
    ++pending_base_;
  }
}

// After an optimisation of the back end, the filter takes the loop-closed
// geometry: every landmark moves by the transform that takes its key scan
// from where the filter had it to where the graph has it now. Later
// updates then agree with the closed loop instead of pulling the robot back
// to the drifted map.
std::vector<std::pair<int, Pose2>> BackEndLink::reanchorCorrections(const EkfSlam& filter) {
  std::vector<std::pair<int, Pose2>> corrections = keyCorrections(filter);
  // The estimates at the latest sightings move with their landmarks.
  for (const auto& [id, c] : corrections) {
    const auto seen = point_seen_at_.find(id);
    if (seen != point_seen_at_.end()) seen->second = transformFrom(c, seen->second);
  }
  const BackEndView& view = *view_;
  for (size_t k = 0; k < key_filtered_.size(); ++k) {
    key_filtered_[k] = compose(*map_from_graph_, view.key_poses[k]);
  }
  return corrections;
}

std::vector<std::pair<int, Pose2>> BackEndLink::landmarkCorrections(const EkfSlam& filter) const {
  std::vector<std::pair<int, Pose2>> corrections = keyCorrections(filter);
  for (auto& [id, c] : corrections) {
    const auto seen = point_seen_at_.find(id);
    if (seen == point_seen_at_.end()) continue;
    // First back to the latest sighting's estimate, then with the key scan.
    const Vector2 back = seen->second - filter.landmarkPosition(filter.slotOf(id));
    c = compose(c, Pose2(back.x(), back.y(), 0.0));
  }
  return corrections;
}

std::vector<std::pair<int, Pose2>> BackEndLink::keyCorrections(const EkfSlam& filter) const {
  std::vector<std::pair<int, Pose2>> corrections;
  if (!view_ || !map_from_graph_) return corrections;
  const BackEndView& view = *view_;
  corrections.reserve(filter.landmarks().size());
  for (const LandmarkInfo& info : filter.landmarks()) {
    const auto it = landmark_scan_.find(info.id);
    if (it == landmark_scan_.end()) continue;
    const int k = view.keyAtOrBefore(it->second);
    if (k < 0 || k >= static_cast<int>(key_filtered_.size())) continue;
    const Pose2 key_map = compose(*map_from_graph_, view.key_poses[k]);
    corrections.emplace_back(info.id, compose(key_map, inverse(key_filtered_[k])));
  }
  return corrections;
}

// landmark_scan_ and point_seen_at_ lose only landmarks the filter no longer holds (ids
// are never reused).
void BackEndLink::forgetBefore(long first_record, const EkfSlam& filter) {
  size_t loop_scans = 0;
  while (loop_scans < record_of_loop_scan_.size() &&
         record_of_loop_scan_[loop_scans] < first_record) {
    ++loop_scans;
  }
  record_of_loop_scan_.erase(record_of_loop_scan_.begin(),
                             record_of_loop_scan_.begin() + loop_scans);
  first_loop_scan_ += static_cast<int>(loop_scans);
  const auto forgetGone = [&](auto* by_id) {
    for (auto it = by_id->begin(); it != by_id->end();) {
      it = filter.slotOf(it->first) < 0 ? by_id->erase(it) : std::next(it);
    }
  };
  forgetGone(&landmark_scan_);
  forgetGone(&point_seen_at_);
}

BackEndLinkState BackEndLink::state() const {
  BackEndLinkState out;
  if (!back_end_) return out;
  const LoopCloser& closer = back_end_->drained();
  out.closer = closer.state();
  // The filter's pose at the key scans the last view did not report yet.
  out.key_filtered = key_filtered_;
  for (int k = static_cast<int>(key_filtered_.size()); k < closer.keyCount(); ++k) {
    out.key_filtered.push_back(pending_filtered_[closer.keyScanIndex(k) - pending_base_]);
  }
  out.landmark_scan.assign(landmark_scan_.begin(), landmark_scan_.end());
  std::sort(out.landmark_scan.begin(), out.landmark_scan.end());
  out.point_seen_at.assign(point_seen_at_.begin(), point_seen_at_.end());
  std::sort(out.point_seen_at.begin(), out.point_seen_at.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  out.has_map_from_graph = map_from_graph_.has_value();
  if (map_from_graph_) out.map_from_graph = *map_from_graph_;
  out.last_front_end = last_front_end_;
  out.record_of_loop_scan = record_of_loop_scan_;
  return out;
}

std::string BackEndLink::resume(const BackEndLinkState& state, bool same_frame) {
  if (!back_end_) return "";  // loop closure off: the saved key scans are not used
  if (state.key_filtered.size() != state.closer.keys.size()) {
    return "the filter's poses at the key scans do not match the key scans";
  }
  if (const std::string error = back_end_->resume(state.closer); !error.empty()) return error;
  view_ = back_end_->newestView();
  loops_seen_ = view_->counters.accepted;
  // The saved scans' history records (with the history restored, loops to
  // the saved key scans join their iterations in the full smoother).
  record_of_loop_scan_ = state.record_of_loop_scan;
  first_loop_scan_ = state.closer.scan_count - static_cast<int>(record_of_loop_scan_.size());
  key_filtered_ = state.key_filtered;
  pending_filtered_.clear();
  pending_base_ = state.closer.scan_count;
  landmark_scan_ =
      std::unordered_map<int, int>(state.landmark_scan.begin(), state.landmark_scan.end());
  point_seen_at_ =
      std::unordered_map<int, Vector2>(state.point_seen_at.begin(), state.point_seen_at.end());
  map_from_graph_.reset();
  if (state.has_map_from_graph) map_from_graph_ = state.map_from_graph;
  last_front_end_ = state.last_front_end;
  front_end_offset_.reset();
  resume_at_ = state.closer.keys.empty() || same_frame ? std::nullopt
                                                       : std::optional<Pose2>(state.last_front_end);
  return "";
}

std::vector<BackEndLink::KeyScan> BackEndLink::keyScans(bool with_points) const {
  std::vector<KeyScan> out;
  if (!view_ || !map_from_graph_) return out;
  const BackEndView& view = *view_;
  out.resize(view.key_poses.size());
  for (size_t k = 0; k < view.key_poses.size(); ++k) {
    out[k].stamp = view.key_stamps[k];
    out[k].pose = compose(*map_from_graph_, view.key_poses[k]);
    if (with_points) out[k].points = *view.key_points[k];
  }
  return out;
}

void BackEndLink::finish() {
  if (back_end_) back_end_->drained().finish();
}

std::vector<StampedPose> BackEndLink::optimizedScanPoses() const {
  if (!back_end_) return {};
  // The graph lives in the control source's frame (the odometry's heading at
  // the start); the map frame is the filter's, as every other trajectory.
  std::vector<StampedPose> out = back_end_->drained().scanPoses();
  if (map_from_graph_) {
    for (StampedPose& p : out) p.pose = compose(*map_from_graph_, p.pose);
  }
  return out;
}

// The back end's loop edges join key scans; a key scan's pose is its
// iteration's pose composed with the odometry since that iteration, so each
// loop becomes a constraint between two iteration poses with those offsets.
std::vector<IterationConstraint> BackEndLink::loopConstraints(const ScanHistory& history) const {
  std::vector<IterationConstraint> out;
  if (!back_end_) return out;
  const LoopCloser& closer = back_end_->drained();
  // The kept record of loop scan `scan`, or null.
  auto recordOf = [&](int scan) -> const ScanRecord* {
    const int i = scan - first_loop_scan_;
    if (scan < 0 || i < 0 || i >= static_cast<int>(record_of_loop_scan_.size())) return nullptr;
    return history.record(record_of_loop_scan_[i]);
  };
  const int first_iteration = history.firstIteration();
  for (const PoseGraphEdge& edge : closer.graph().edges()) {
    if (!edge.robust || !edge.active) continue;  // sequential edge, or a dropped loop
    const ScanRecord* from = recordOf(closer.keyScanIndex(edge.from));
    const ScanRecord* to = recordOf(closer.keyScanIndex(edge.to));
    if (from == nullptr || to == nullptr) continue;
    const ScanRecord& a = *from;
    const ScanRecord& b = *to;
    if (a.iteration < first_iteration || b.iteration < first_iteration) continue;
    IterationConstraint c;
    c.from_iteration = a.iteration - first_iteration;
    c.to_iteration = b.iteration - first_iteration;
    c.from_offset = between(a.odometry_at_iteration, a.odometry);
    c.to_offset = between(b.odometry_at_iteration, b.odometry);
    c.measurement = edge.measurement;
    c.information = edge.information;
    out.push_back(c);
  }
  return out;
}

// With loop closure on, the back end's optimised trajectory is a far better
// starting point than the filtered one (Intel: 0.04 m against 3.1 m): the
// problem is not convex, and from the filtered poses the loop edges look
// like outliers to their kernel. Each iteration starts at its own scan's
// optimised pose, moved into the map frame (the filter's first pose).
std::vector<Pose2> BackEndLink::loopClosedIterationPoses(const ScanHistory& history) const {
  std::vector<Pose2> out;
  const std::vector<ScanRecord>& records = history.records();
  if (!back_end_ || records.empty()) return out;
  const LoopCloser& closer = back_end_->drained();
  // One pose per loop scan the closer still holds (closer.firstScan() on).
  const std::vector<StampedPose> optimized = closer.scanPoses();
  std::vector<int> loop_scan_of_record(records.size(), -1);
  for (size_t i = 0; i < record_of_loop_scan_.size(); ++i) {
    const long scan = first_loop_scan_ + static_cast<long>(i) - closer.firstScan();
    const long record = record_of_loop_scan_[i] - history.firstScan();
    if (scan < 0 || record < 0) continue;
    if (scan >= static_cast<long>(optimized.size())) break;
    loop_scan_of_record[record] = static_cast<int>(scan);
  }
  const int iterations = static_cast<int>(history.smootherRecord().iterations().size());
  out.assign(iterations, Pose2());
  std::vector<char> found(iterations, 0);
  // The whole run: the first scan's filtered pose ties the graph to the map
  // frame. A bounded history has lost that scan: the frame is the one the
  // key scans are given in (keyScans()), so the window and the older key
  // scans agree.
  bool have_frame = history.firstScan() > 0 && map_from_graph_.has_value();
  Pose2 map_from_graph = map_from_graph_.value_or(Pose2());
  for (size_t r = 0; r < records.size(); ++r) {
    const ScanRecord& record = records[r];
    const int scan = loop_scan_of_record[r];
    if (scan < 0) continue;
    if (!have_frame) {
      // The record's own pose in the map frame, hung off its iteration.
      map_from_graph = compose(record.filtered, inverse(optimized[scan].pose));
      have_frame = true;
    }
    const int k = record.iteration - history.firstIteration();
    if (k < 0 || k >= iterations || found[k]) continue;
    // The iteration's pose = the scan's pose minus the odometry since it.
    out[k] = compose(compose(map_from_graph, optimized[scan].pose),
                     inverse(between(record.odometry_at_iteration, record.odometry)));
    found[k] = 1;
  }
  for (int k = 0; k < iterations; ++k) {
    if (!found[k]) return {};  // an iteration without a scan in the graph: keep the filter's
  }
  return out;
}

}  // namespace ekf_slam
