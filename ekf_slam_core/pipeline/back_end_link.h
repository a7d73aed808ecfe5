// The pipeline's link to the loop-closing back end (a pose graph over key
// scans, inline or on its own thread: loop_closure/back_end.h). It hands
// every scan to the back end, turns the view the scan is given into the
// causal estimate in the map frame, and remembers what a correction needs:
// the filter's pose at each key scan and the loop scan that last observed
// each landmark, so that after an optimisation the filter can take the
// loop-closed geometry (re-anchoring). After the run it turns the graph's
// loops into constraints between the filter's iterations, and its
// optimised trajectory into starting poses, for the full smoother.
#pragma once

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ekf_slam_core/loop_closure/back_end.h"
#include "ekf_slam_core/pipeline/pipeline_options.h"
#include "ekf_slam_core/pipeline/scan_history.h"
#include "ekf_slam_core/pipeline/slam_state.h"

namespace ekf_slam {

class BackEndLink {
 public:
  // Inactive (every call a no-op, empty results) without loop closure.
  explicit BackEndLink(const PipelineOptions& options);

  bool active() const { return back_end_ != nullptr; }

  struct Step {
    Pose2 causal;            // the loop-closed estimate for the scan (map frame)
    bool new_loops = false;  // the back end accepted loops since the last scan
  };
  // Every scan with a usable odometry, in order: `odometry` is the control
  // source's pose, `filtered` the pose the filter gave the scan, `record`
  // the scan's number in the history, `observed` the ids of the landmarks
  // the scan matched or created, `filter` the filter after the scan's update.
  Step addScan(double stamp, const Scan& scan, const Pose2& odometry, bool usable,
               const Pose2& filtered, long record, const std::vector<int>& observed,
               const EkfSlam& filter);

  // After new loops: per landmark of `filter` last observed at a known
  // loop scan, the transform that takes the key scan at or before it
  // from where the filter had it to where the graph has it now. The key
  // scans are taken as re-anchored.
  std::vector<std::pair<int, Pose2>> reanchorCorrections(const EkfSlam& filter);
  // Where each landmark is drawn in the graph's frame now, as a transform
  // of its place in `filter`: the key scan's correction (the key scans left
  // as they are) applied, for a point landmark, to where the filter had it
  // right after its latest sighting. Between sightings the filter moves a
  // landmark with every correction of the robot (their correlation: a
  // heading update swings the corners behind the robot round it), while
  // its key scan stays where the graph put it; drawn with those moves,
  // landmarks passed minutes ago stood in the corridors of the grid.
  std::vector<std::pair<int, Pose2>> landmarkCorrections(const EkfSlam& filter) const;

  // The history dropped its records before `first_record`: so are the
  // loop scans that hang off them, and the landmarks `filter` no longer holds.
  void forgetBefore(long first_record, const EkfSlam& filter);

  // The back end's key scans as the last scan saw them (loop-closed, map
  // frame), with their readings in the robot frame when asked.
  struct KeyScan {
    double stamp = 0.0;
    Pose2 pose;
    std::vector<Vector2> points;
  };
  std::vector<KeyScan> keyScans(bool with_points) const;
  // The graph's loops between those key scans (indices into keyScans()).
  std::vector<LoopLink> loops() const { return view_ ? view_->loops : std::vector<LoopLink>(); }
  long optimisations() const { return view_ ? view_->counters.optimisations : 0; }
  LoopClosureCounters counters() const { return view_ ? view_->counters : LoopClosureCounters(); }
  long backlog() const { return back_end_ ? back_end_->backlog() : 0; }

  // What continuing needs (slam_state.h), once the back end has processed
  // every scan handed to it; empty without loop closure.
  BackEndLinkState state() const;
  // Continues from `state` before the first scan: the back end takes the
  // saved key scans and graph, and the next scan's front-end pose is taken
  // to be where the saved run stopped (the front end of the new run starts
  // in a frame of its own). Empty on success, else what is inconsistent.
  // `same_frame`: the new front end goes on in the saved one's frame (its
  // map was restored) from where the saved run stopped, so no offset is
  // needed (false for a robot placed elsewhere: the first new scan hangs at
  // state.last_front_end).
  std::string resume(const BackEndLinkState& state, bool same_frame);
  // After resume(): the robot moved by `motion` (its frame) since the save.
  void resumeMovedBy(const Pose2& motion) {
    if (resume_at_) resume_at_ = compose(*resume_at_, motion);
  }
  // A control-source pose in the back end's front-end frame (after a
  // resume, the saved run's).
  Pose2 frontEndPose(const Pose2& odometry) const {
    return front_end_offset_ ? compose(*front_end_offset_, odometry) : odometry;
  }

  // The final optimisation after the last scan; then one pose per scan, in
  // the map frame.
  void finish();
  std::vector<StampedPose> optimizedScanPoses() const;
  const LoopCloser* loopCloser() const { return back_end_ ? &back_end_->drained() : nullptr; }

  // For the full smoother over `history`: the graph's loop edges as
  // constraints between iterations (a loop with an end before the kept
  // history is left out), and one starting pose per kept iteration from
  // the optimised graph (empty when an iteration has no scan in it).
  std::vector<IterationConstraint> loopConstraints(const ScanHistory& history) const;
  std::vector<Pose2> loopClosedIterationPoses(const ScanHistory& history) const;

 private:
  // The filter's pose at each key scan the back end has reported.
  void trackKeyScans();
  // Per landmark last observed at a known loop scan, the transform that
  // takes its key scan from where the filter had it to where the graph has
  // it now.
  std::vector<std::pair<int, Pose2>> keyCorrections(const EkfSlam& filter) const;

  Pose2 laser_pose_;
  // The back end by pointer (it may run a thread of its own); a copy of the
  // link copies it (LoopClosureBackEnd's copy: its state, a thread of its
  // own), so that the link is a value too.
  struct CopiedBackEnd : std::unique_ptr<LoopClosureBackEnd> {
    CopiedBackEnd(std::unique_ptr<LoopClosureBackEnd> back_end)  // NOLINT: implicit on purpose
        : std::unique_ptr<LoopClosureBackEnd>(std::move(back_end)) {}
    CopiedBackEnd(const CopiedBackEnd& other)
        : std::unique_ptr<LoopClosureBackEnd>(other ? std::make_unique<LoopClosureBackEnd>(*other)
                                                    : nullptr) {}
    CopiedBackEnd(CopiedBackEnd&&) = default;
    CopiedBackEnd& operator=(CopiedBackEnd&&) = default;
  };
  CopiedBackEnd back_end_;                   // null when loop closure is off
  std::shared_ptr<const BackEndView> view_;  // the back end as the last scan saw it
  long loops_seen_ = 0;                      // accepted loops in that view
  // History record of each scan given to the back end (from loop scan
  // first_loop_scan_ on; both count from the run's first).
  std::vector<long> record_of_loop_scan_;
  int first_loop_scan_ = 0;
  std::vector<Pose2> key_filtered_;     // the filter's pose at each key scan (map frame)
  std::deque<Pose2> pending_filtered_;  // the filter's pose at loop scans pending_base_ …
  long pending_base_ = 0;               // … on, whose key scans the back end may still report
  std::unordered_map<int, int> landmark_scan_;  // landmark id → loop scan last observing it
  // Point landmark id → the filter's estimate right after its latest
  // sighting (map frame; moved with its key scan by re-anchoring).
  std::unordered_map<int, Vector2> point_seen_at_;
  std::optional<Pose2> map_from_graph_;  // the graph's frame in the map frame (first scan)
  Pose2 last_front_end_;                 // the back end's front-end pose at the last scan
  // After a resume: where the saved run stopped (until the first scan) and
  // then the transform from the new front end's frame to the saved one's.
  std::optional<Pose2> resume_at_;
  std::optional<Pose2> front_end_offset_;
};

}  // namespace ekf_slam
