#include "ekf_slam_ros/slam_node/slam_diagnostics.h"

#include <algorithm>
#include <sstream>
#include <string>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {

using diagnostic_updater::DiagnosticStatusWrapper;

SlamDiagnostics::Timing::~Timing() {
  times_->add(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
}

SlamDiagnostics::SlamDiagnostics(ros::NodeHandle node, ros::NodeHandle private_node,
                                 const SlamNodeParams& params, const PipelineOptions& pipeline,
                                 const Sources& sources)
    : params_(params),
      loop_closure_(pipeline.loop_closure.enabled),
      mecp_(pipeline.landmarks == LandmarkSet::kPointsAndMecp),
      sources_(sources),
      updater_(node, private_node) {
  updater_.setHardwareID("ekf_slam");
  updater_.add("EKF-SLAM", this, &SlamDiagnostics::diagnose);
  last_time_ = last_published_ = ros::WallTime::now();
  // On wall time, every ~diagnostic_period (the updater's): /diagnostics
  // keeps coming when a simulated clock stops (a bag ended or paused) or
  // jumps back (a looped bag), where a ROS timer and Updater::update() wait
  // for the clock.
  timer_ = node.createWallTimer(ros::WallDuration(0.1), [this](const ros::WallTimerEvent&) {
    const ros::WallTime now = ros::WallTime::now();
    if ((now - last_published_).toSec() < updater_.getPeriod()) return;
    last_published_ = now;
    updater_.force_update();
  });
}

void SlamDiagnostics::addIteration(const ScanResult& result) {
  for (double nis : result.iteration.nis) {
    nis_window_.push_back(nis);
    if (static_cast<int>(nis_window_.size()) > params_.nis_window) nis_window_.pop_front();
  }
}

void SlamDiagnostics::restart() {
  nis_window_.clear();
  iterations_at_last_ = 0;
}

void SlamDiagnostics::diagnose(DiagnosticStatusWrapper& status) {
  const SlamPipeline* pipeline = sources_.slam->pipeline();
  const ros::WallTime now = ros::WallTime::now();
  const double period = (now - last_time_).toSec();
  const PipelineCounters counters = pipeline ? pipeline->counters() : PipelineCounters{};
  const long iterations = counters.iterations;
  const double rate = period > 0.0 ? std::max(0L, iterations - iterations_at_last_) / period : 0.0;
  iterations_at_last_ = iterations;
  last_time_ = now;

  // Inputs rejected: by the node (a pause is not a fault) or by the filter.
  const long drops = sources_.drops->faults() + counters.time_not_increasing +
                     counters.odometry_jumps + counters.bad_input + counters.update_failures;
  const bool nis_inside = addNisBand(status);
  addScanMatching(counters, status);
  if (pipeline && loop_closure_) addBackEnd(counters, status);
  if (mecp_) {
    status.add("MECP polygons", counters.mecp_polygons);
    status.add("MECP group matches", counters.mecp_group_matches);
    status.add("MECP: centre fitted, corners did not", counters.mecp_group_refused);
    status.add("MECP: pairings changed by the group", counters.mecp_pairings_changed);
    status.add("MECP polygons remembered", counters.mecp_remembered);
  }
  addRearAndMap(status);
  const RearCounters rear = sources_.rear ? sources_.rear->counters() : RearCounters{};
  const long alone = rear.alone_no_rear + rear.alone_no_transform;
  summarise(drops, alone, nis_inside, status);
  drops_at_last_ = drops;
  alone_at_last_ = alone;
  addCounts(counters, iterations, rate, status);
}

double SlamDiagnostics::nisAverage() const {
  double average = 0.0;
  for (double nis : nis_window_) average += nis;
  if (!nis_window_.empty()) average /= static_cast<int>(nis_window_.size());
  return average;
}

bool SlamDiagnostics::addNisBand(DiagnosticStatusWrapper& status) const {
  const int samples = static_cast<int>(nis_window_.size());
  if (samples == 0) {
    status.add("NIS 95% band", "no matches yet");
    return true;
  }
  const ChiSquareBand band = averageChiSquareBand(2.0, samples, 0.95);
  const double average = nisAverage();
  std::ostringstream text;
  text.precision(3);
  text << "[" << band.lower << ", " << band.upper << "]";
  status.add("NIS 95% band", text.str());
  return average >= band.lower && average <= band.upper;
}

void SlamDiagnostics::addScanMatching(const PipelineCounters& counters,
                                      DiagnosticStatusWrapper& status) const {
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
}

void SlamDiagnostics::addBackEnd(const PipelineCounters& counters,
                                 DiagnosticStatusWrapper& status) const {
  // As the last scan saw the back end (never waits for its thread).
  const SlamPipeline& pipeline = *sources_.slam->pipeline();
  const LoopClosureCounters loops = pipeline.backEndCounters();
  status.add("back-end backlog (scans)", pipeline.backEndBacklog());
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

void SlamDiagnostics::addRearAndMap(DiagnosticStatusWrapper& status) const {
  if (sources_.rear) {
    const RearCounters& rear = sources_.rear->counters();
    status.add("rear scans received", rear.received);
    status.add("rear scans refused", rear.refused);
    status.add("scans merged with a rear scan", rear.merged);
    status.add("scans without the rear laser: none within rear_scan_tolerance", rear.alone_no_rear);
    status.add("scans without the rear laser: rear transforms missing", rear.alone_no_transform);
  }
  if (const LiveMapPublisher* live = sources_.grids->liveMap()) {
    status.add("maps published", live->published());
    status.add("last map build [s]", live->lastBuildSeconds());
  }
}

void SlamDiagnostics::summarise(long drops, long alone, bool nis_inside,
                                DiagnosticStatusWrapper& status) const {
  if (sources_.services->paused()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "paused");
  } else if (!laser_frame_.empty() && laser_mount_.tilt > params_.max_laser_tilt) {
    std::ostringstream text;
    text.setf(std::ios::fixed);
    text.precision(1);
    text << params_.base_frame << " -> " << laser_frame_ << " is tilted "
         << radToDeg(laser_mount_.tilt) << " deg from level (roll " << radToDeg(laser_mount_.roll)
         << ", pitch " << radToDeg(laser_mount_.pitch) << " deg; max_laser_tilt "
         << radToDeg(params_.max_laser_tilt) << "): the scan plane is not the floor's";
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, text.str());
  } else if (drops > drops_at_last_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   std::to_string(drops - drops_at_last_) +
                       " inputs rejected since the last report (see counters)");
  } else if (sources_.rear && alone > alone_at_last_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   std::to_string(alone - alone_at_last_) +
                       " scans used without the rear laser since the last report (see counters)");
  } else if (!nis_inside) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "average NIS outside its 95% band (filter inconsistent)");
  } else if (sources_.relocaliser->status().lost) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "lost: the scans do not fit the saved map; searching it for the robot");
  } else if (!sources_.slam->pipeline()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for the first scan");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "mapping");
  }
}

void SlamDiagnostics::addCounts(const PipelineCounters& counters, long iterations, double rate,
                                DiagnosticStatusWrapper& status) const {
  const SlamPipeline* pipeline = sources_.slam->pipeline();
  status.add("paused", sources_.services->paused());
  status.add("steps (~step)", sources_.services->steps());
  if (pipeline) status.add("large moves made while paused, kept", counters.accepted_large_moves);
  status.add("localize only", sources_.slam->localizeOnly());
  status.add("relocalisations (initialpose)", sources_.services->relocalisations());
  const Relocaliser::Status relocaliser = sources_.relocaliser->status();
  status.add("lost: watched in the loaded state", relocaliser.watching);
  if (relocaliser.watching) {
    status.addf("fit to the saved map", "%.3f", relocaliser.score);
    status.add("lost", relocaliser.lost);
    status.add("times lost", relocaliser.times_lost);
    status.add("times found again (global search)", relocaliser.times_found);
    status.add("global searches", relocaliser.searches);
    status.add("last global search",
               relocaliser.last_search.empty() ? std::string("placed") : relocaliser.last_search);
    if (!relocaliser.map_error.empty())
      status.add("saved map not searchable", relocaliser.map_error);
  }
  status.add("scans received", sources_.input->received());
  status.add("scans waiting for transforms", sources_.input->waiting());
  status.add("scans processed", pipeline ? counters.scans : 0L);
  status.add("processing time p50 [ms]", 1e3 * processing_times_->percentile(50.0));
  status.add("processing time p99 [ms]", 1e3 * processing_times_->percentile(99.0));
  status.add("processing time max [ms]", 1e3 * processing_times_->max());
  status.add("iterations", iterations);
  // The history ~smooth re-solves (at most 9/8 of history_max_scans).
  status.add("scans kept for smoothing",
             pipeline ? static_cast<long>(pipeline->scans().size()) : 0L);
  status.addf("iteration rate (Hz)", "%.2f", rate);
  status.add("landmarks", pipeline ? pipeline->filter().landmarkCount() : 0);
  status.add("state size", pipeline ? pipeline->filter().stateDim() : EkfSlam::kPoseDim);
  status.addf("NIS average", "%.3f", nisAverage());
  status.add("NIS samples", static_cast<int>(nis_window_.size()));
  for (const auto& [reason, count] : sources_.drops->counts()) {
    status.add(std::string("dropped: ") + toString(reason), count);
  }
  status.add("dropped tf: stamp in the future", sources_.transforms->refusedFuture());
  status.add("dropped tf: invalid", sources_.transforms->refusedInvalid());
  status.add("rejected by filter: time not increasing", counters.time_not_increasing);
  status.add("rejected by filter: odometry jump", counters.odometry_jumps);
  status.add("rejected by filter: bad input", counters.bad_input);
  status.add("rejected by filter: update refused", counters.update_failures);
  status.add("laser pose changes", laser_pose_changes_);
  if (!laser_frame_.empty()) {
    status.add("laser mount", laser_mount_.inverted ? "upside down (scans mirrored)" : "upright");
    status.addf("laser tilt [deg]", "%.2f", radToDeg(laser_mount_.tilt));
  }
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  // What the node's heap holds (allocated chunks, mmapped ones included),
  // as against the resident set, which also counts the pages the allocator
  // keeps free: a soak tells a growing heap from a fragmented one by it.
  const struct mallinfo2 heap = mallinfo2();
  status.add("heap in use [KiB]", static_cast<long>((heap.uordblks + heap.hblkhd) / 1024));
#endif
}

}  // namespace ekf_slam
