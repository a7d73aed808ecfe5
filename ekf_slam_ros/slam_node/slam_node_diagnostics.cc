// ekf_slam_node's /diagnostics: inputs, drops by reason, the filter's
// health, the back end and the map.
#include "ekf_slam_ros/slam_node/slam_node.h"

#include <sstream>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {

void SlamNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const ros::WallTime now = ros::WallTime::now();
  const double period = (now - last_diagnostic_time_).toSec();
  const long iterations = pipeline_ ? pipeline_->counters().iterations : 0;
  const double rate =
      period > 0.0 ? std::max(0L, iterations - iterations_at_last_diagnostic_) / period : 0.0;
  iterations_at_last_diagnostic_ = iterations;
  last_diagnostic_time_ = now;

  long drops = 0;
  for (const auto& [reason, count] : drops_) {
    if (reason != DropReason::kPaused) drops += count;
  }
  const PipelineCounters counters = pipeline_ ? pipeline_->counters() : PipelineCounters{};
  const long pipeline_rejects = counters.time_not_increasing + counters.odometry_jumps +
                                counters.bad_input + counters.update_failures;
  drops += pipeline_rejects;

  double nis_average = 0.0;
  for (double nis : nis_window_) nis_average += nis;
  const int samples = static_cast<int>(nis_window_.size());
  if (samples > 0) nis_average /= samples;
  bool nis_inside = true;
  if (samples > 0) {
    const ChiSquareBand band = averageChiSquareBand(2.0, samples, 0.95);
    nis_inside = nis_average >= band.lower && nis_average <= band.upper;
    std::ostringstream text;
    text.precision(3);
    text << "[" << band.lower << ", " << band.upper << "]";
    status.add("NIS 95% band", text.str());
  } else {
    status.add("NIS 95% band", "no matches yet");
  }
  status.add("scan matches refused (disagree with the wheels)",
             counters.front_end.refused_by_odometry);
  status.add("scan matches refused (all reasons)", counters.scan_match_refusals);
  status.add("scan matches refused (correction beyond the bounds)",
             counters.front_end.refused_by_correction);
  status.add("scan matches refused (too few points, pairs or inliers)",
             counters.front_end.refused_by_fit);
  if (counters.local_matcher_runs) {
    // The second matcher, whose moves are the full smoother's motion edges.
    const ScanMatcherCounters& local = counters.local_matcher;
    status.add("local matcher: moves refused (all reasons)", local.refused);
    status.add("local matcher: moves refused (disagree with the wheels)",
               local.refused_by_odometry);
    status.add("local matcher: moves refused (correction beyond the bounds)",
               local.refused_by_correction);
    status.add("local matcher: moves refused (too few points, pairs or inliers)",
               local.refused_by_fit);
  }
  if (pipeline_ && config_.pipeline.loop_closure.enabled) {
    // As the last scan saw the back end (never waits for its thread).
    const LoopClosureCounters loops = pipeline_->backEndCounters();
    status.add("back-end backlog (scans)", pipeline_->backEndBacklog());
    status.add("key scans", loops.key_scans);
    status.add("key scans without readings (place full)", loops.released);
    status.add("loops accepted", loops.accepted);
    status.add("loop candidates refused", loops.refused);
    status.add("loop candidates refused (score under min_score)", loops.refused_by_score);
    status.add("loop candidates refused (fine match failed)", loops.refused_by_fit);
    status.add("loop candidates refused (sliding along a corridor)", loops.refused_as_degenerate);
    status.add("loop candidates refused as ambiguous", loops.ambiguous);
    status.add("loops refused as inconsistent", loops.inconsistent);
    status.add("wide-window matches never confirmed", loops.unconfirmed);
    status.add("filter re-anchored", counters.reanchors);
  }
  if (config_.pipeline.landmarks == LandmarkSet::kPointsAndMecp) {
    status.add("MECP updates", counters.mecp_updates);
    status.add("MECP: no polygon around the robot", counters.mecp_without_polygon);
    status.add("MECP: skipped (centre too near, or refused)", counters.mecp_skipped);
  }
  const bool rear = !params_.rear_scan_topic.empty();
  const long alone = alone_no_rear_ + alone_no_transform_;
  if (rear) {
    status.add("rear scans received", rear_received_);
    status.add("rear scans refused", rear_refused_);
    status.add("scans merged with a rear scan", merged_scans_);
    status.add("scans without the rear laser: none within rear_scan_tolerance", alone_no_rear_);
    status.add("scans without the rear laser: rear transforms missing", alone_no_transform_);
  }
  if (live_map_) {
    status.add("maps published", live_map_->published());
    status.add("last map build [s]", live_map_->lastBuildSeconds());
  }

  if (paused_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "paused");
  } else if (drops > drops_at_last_diagnostic_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   std::to_string(drops - drops_at_last_diagnostic_) +
                       " inputs rejected since the last report (see counters)");
  } else if (rear && alone > alone_at_last_diagnostic_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   std::to_string(alone - alone_at_last_diagnostic_) +
                       " scans used without the rear laser since the last report (see counters)");
  } else if (!nis_inside) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "average NIS outside its 95% band (filter inconsistent)");
  } else if (!pipeline_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for the first scan");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "mapping");
  }
  drops_at_last_diagnostic_ = drops;
  alone_at_last_diagnostic_ = alone;

  status.add("paused", paused_);
  status.add("steps (~step)", steps_done_);
  if (pipeline_)
    status.add("large moves made while paused, kept", pipeline_->counters().accepted_large_moves);
  status.add("localize only", localize_only_);
  status.add("relocalisations (initialpose)", relocalisations_);
  status.add("scans received", scans_received_);
  status.add("scans processed", pipeline_ ? counters.scans : 0L);
  status.add("processing time p50 [ms]", 1e3 * processing_times_->percentile(50.0));
  status.add("processing time p99 [ms]", 1e3 * processing_times_->percentile(99.0));
  status.add("processing time max [ms]", 1e3 * processing_times_->max());
  status.add("iterations", iterations);
  // The history ~smooth re-solves (at most 9/8 of history_max_scans).
  status.add("scans kept for smoothing",
             pipeline_ ? static_cast<long>(pipeline_->scans().size()) : 0L);
  status.addf("iteration rate (Hz)", "%.2f", rate);
  status.add("landmarks", pipeline_ ? pipeline_->filter().landmarkCount() : 0);
  status.add("state size", pipeline_ ? pipeline_->filter().stateDim() : EkfSlam::kPoseDim);
  status.addf("NIS average", "%.3f", nis_average);
  status.add("NIS samples", samples);
  for (const auto& [reason, count] : drops_) {
    status.add(std::string("dropped: ") + toString(reason), count);
  }
  status.add("dropped tf: stamp in the future", tf_listener_.refusedFuture());
  status.add("dropped tf: invalid", tf_listener_.refusedInvalid());
  status.add("rejected by filter: time not increasing", counters.time_not_increasing);
  status.add("rejected by filter: odometry jump", counters.odometry_jumps);
  status.add("rejected by filter: bad input", counters.bad_input);
  status.add("rejected by filter: update refused", counters.update_failures);
  status.add("laser pose changes", laser_pose_changes_);
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  // What the node's heap holds (allocated chunks, mmapped ones included),
  // as against the resident set, which also counts the pages the allocator
  // keeps free: a soak tells a growing heap from a fragmented one by it.
  const struct mallinfo2 heap = mallinfo2();
  status.add("heap in use [KiB]", static_cast<long>((heap.uordblks + heap.hblkhd) / 1024));
#endif
}

}  // namespace ekf_slam
