#include "ekf_slam_core/pipeline/slam_pipeline.h"

#include <cmath>
#include <sstream>

namespace ekf_slam {
namespace {

// The landmarks a scan matched or created, points and lines: each then
// hangs off this scan's key scan when a loop closure moves the map.
std::vector<int> observedIds(const ScanResult& result) {
  std::vector<int> ids = result.iteration.new_landmark_ids;
  ids.insert(ids.end(), result.lines.new_landmark_ids.begin(), result.lines.new_landmark_ids.end());
  for (const PointMatch& m : result.iteration.matches) ids.push_back(m.landmark_id);
  for (const LineMatch& m : result.lines.matches) ids.push_back(m.landmark_id);
  return ids;
}

ScanHistory emptyHistory(const PipelineOptions& options) {
  return ScanHistory(options.history_scans, options.initial_pose, options.initial_pose_covariance,
                     {options.keep_readings, options.readings_grid, options.filter.laser_pose});
}

}  // namespace

SlamPipeline::SlamPipeline(const PipelineOptions& options)
    : options_(options),
      front_end_(options),
      filter_(options),
      back_end_(options),
      history_(emptyHistory(options)) {}

PipelineCounters SlamPipeline::counters() const {
  PipelineCounters out;
  static_cast<ScanCounters&>(out) = counters_;
  static_cast<FrontEndCounters&>(out) = front_end_.counters();
  static_cast<FilterCounters&>(out) = filter_.counters();
  return out;
}

// Against the robot's raw odometry frame (what odom → base_link on tf
// carries), also when the control is scan-matched.
Pose2 SlamPipeline::mapToOdom() const {
  return compose(filter_.filter().pose(), inverse(last_raw_odometry_));
}

SlamState SlamPipeline::state(const std::string& configuration) const {
  SlamState out;
  out.configuration = configuration;
  out.laser_pose = options_.filter.laser_pose;
  out.filter = filter_.filter().filterState();
  out.line_support = filter_.lineSupport();
  out.back_end = back_end_.state();
  if (std::optional<ScanMatchingOdometryState> front_end = front_end_.state()) {
    out.has_front_end = true;
    out.front_end = std::move(*front_end);
  }
  out.history = history_.state();
  keepNewestScans(kSavedHistoryScans, &out.history);
  // The loop closer's per-scan entries and their records likewise.
  const auto keepNewest = [](auto* entries) {
    if (static_cast<long>(entries->size()) > kSavedHistoryScans) {
      entries->erase(entries->begin(), entries->end() - kSavedHistoryScans);
    }
  };
  keepNewest(&out.back_end.closer.scans);
  keepNewest(&out.back_end.record_of_loop_scan);
  out.scans = counters_.scans + resumed_scans_;
  if (initialised_) {
    // Resumed from the last iteration, where the filter's pose is.
    out.back_end.last_front_end = back_end_.frontEndPose(last_odometry_);
    out.has_last_iteration = true;
    out.last_stamp = last_stamp_;
    out.last_raw_odometry = last_raw_odometry_;
  }
  return out;
}

std::string SlamPipeline::resume(const SlamState& state, ResumeAt at) {
  if (initialised_ || counters_.scans > 0) {
    return "a saved state can be resumed only before the first scan";
  }
  const Pose2 mount = between(options_.filter.laser_pose, state.laser_pose);
  if (std::hypot(mount.x, mount.y) > 0.01 || std::abs(mount.theta) > 0.5 * kPi / 180.0) {
    std::ostringstream message;
    message << "the state was made with the laser at (" << state.laser_pose.x << ", "
            << state.laser_pose.y << ", " << state.laser_pose.theta
            << ") on the robot, this configuration has it at (" << options_.filter.laser_pose.x
            << ", " << options_.filter.laser_pose.y << ", " << options_.filter.laser_pose.theta
            << "): another laser mount (its key scans would not fit)";
    return message.str();
  }
  if (const std::string error = history_.restore(state.history); !error.empty()) return error;
  // The front end goes on in the saved frame when its map was saved, and
  // the back end then needs no offset between the two runs' frames.
  const bool same_frame = state.has_front_end && front_end_.restore(state.front_end);
  if (const std::string error =
          back_end_.resume(state.back_end, same_frame && at == ResumeAt::kWhereItStopped);
      !error.empty()) {
    front_end_ = FrontEnd(options_);
    history_ = emptyHistory(options_);
    return error;
  }
  filter_.mutableFilter().restore(state.filter);
  filter_.seedLineSupport(state.line_support);
  resumed_scans_ = state.scans;
  resume_from_.reset();
  if (state.has_last_iteration) resume_from_.emplace(state.last_stamp, state.last_raw_odometry);
  return "";
}

ScanResult SlamPipeline::processScan(const Scan& scan, const Pose2& odometry) {
  return process(scan.stamp, &scan, nullptr, odometry);
}

ScanResult SlamPipeline::processFeatures(double stamp, const FeatureSet& features,
                                         const Pose2& odometry) {
  return process(stamp, nullptr, &features, odometry);
}

std::string SlamPipeline::inputError(const Scan* scan, const FeatureSet* features) const {
  if (scan != nullptr) return validateScan(*scan);
  if (front_end_.matchesScans()) {
    return "features given without their scan, but scan matching (enabled) needs the scan";
  }
  if (back_end_.active()) {
    return "features given without their scan, but loop closure (enabled) needs the scan";
  }
  return validateFeatureSet(*features);
}

ScanResult SlamPipeline::process(double stamp, const Scan* scan, const FeatureSet* features,
                                 const Pose2& raw_odometry) {
  ++counters_.scans;
  current_raw_odometry_ = raw_odometry;
  const std::string input_error = inputError(scan, features);
  const bool usable = usableOdometry(raw_odometry) && input_error.empty() && std::isfinite(stamp);
  // Below, `odometry` is the control source's pose: scan-matched or raw.
  Pose2 odometry = raw_odometry;
  if (usableOdometry(raw_odometry)) {
    bool jumped = false;
    odometry = front_end_.track(scan, raw_odometry, usable, !accept_next_motion_, &jumped);
    if (jumped) ++counters_.odometry_jumps;
  }
  ScanResult out;
  if (!usable) {
    rejectInput(stamp, scan, odometry, input_error, &out);
    return out;
  }
  if (!initialised_ && resume_from_) continueFromSave(stamp, raw_odometry, odometry);
  if (!initialised_) {
    last_odometry_ = odometry;
    last_raw_odometry_ = raw_odometry;
    last_stamp_ = stamp;
    initialised_ = true;
    iterate(stamp, scan, features, odometry, /*predict=*/false, 0.0, &out);
    record(stamp, scan, odometry, usable, &out);
    return out;
  }
  const double dt = stamp - last_stamp_;
  const Pose2 motion = between(last_odometry_, odometry);
  if (!(dt > 0.0)) {
    ++counters_.time_not_increasing;
    out.outcome = ScanOutcome::kSkippedTimeNotIncreasing;
    std::ostringstream message;
    message.precision(6);
    message << std::fixed << "scan stamp " << stamp << " is not after the last iteration's "
            << last_stamp_ << " (" << dt << " s): scan not used for an update";
    out.message = message.str();
    deadReckon(odometry, &out);
  } else if ((options_.min_travel_distance > 0.0 || options_.min_travel_angle > 0.0) &&
             std::hypot(motion.x, motion.y) < options_.min_travel_distance &&
             std::abs(motion.theta) < options_.min_travel_angle) {
    ++counters_.skipped_no_motion;
    out.outcome = ScanOutcome::kSkippedNoMotion;
    deadReckon(odometry, &out);
  } else {
    iterate(stamp, scan, features, odometry, /*predict=*/true, dt, &out);
  }
  record(stamp, scan, odometry, usable, &out);
  return out;
}

void SlamPipeline::continueFromSave(double stamp, const Pose2& raw_odometry,
                                    const Pose2& odometry) {
  const auto [saved_stamp, saved_raw_odometry] = *resume_from_;
  resume_from_.reset();
  const double gap = stamp - saved_stamp;
  const Pose2 since = between(saved_raw_odometry, raw_odometry);
  const bool continues =
      gap > 0.0 && gap <= kResumeGap &&
      !options_.filter.isJump(controlFromOdometry(saved_raw_odometry, raw_odometry));
  if (!continues) return;  // the robot stands where the saved run stopped
  // The saved iteration, seen from this scan through the wheels' motion: the
  // next step predicts across it as if the run had not stopped.
  last_odometry_ = compose(odometry, inverse(since));
  last_raw_odometry_ = saved_raw_odometry;
  last_stamp_ = saved_stamp;
  initialised_ = true;
  back_end_.resumeMovedBy(since);
}

void SlamPipeline::rejectInput(double stamp, const Scan* scan, const Pose2& odometry,
                               const std::string& input_error, ScanResult* out) {
  ++counters_.bad_input;
  out->outcome = ScanOutcome::kRejectedBadInput;
  out->message = !usableOdometry(odometry) ? "odometry pose is not finite or beyond 1e6 m"
                 : !input_error.empty()    ? input_error
                                           : "scan stamp is not finite";
  if (!usableOdometry(odometry)) {
    out->pose = filter_.filter().pose();
    out->pose_covariance = filter_.filter().poseCovariance();
    out->causal_pose = out->pose;
    return;  // no usable odometry: nothing to record against
  }
  if (!initialised_) {
    out->pose = options_.initial_pose;
    out->pose_covariance = Matrix3::Zero();
    out->causal_pose = out->pose;
    return;
  }
  deadReckon(odometry, out);
  out->causal_pose = out->pose;
  // An unusable scan still goes to the back end (which keeps its scan
  // count in step) and into the history.
  record(stamp, scan, odometry, /*usable=*/false, out);
}

void SlamPipeline::deadReckon(const Pose2& odometry, ScanResult* out) const {
  out->pose = filter_.deadReckoned(last_odometry_, odometry);
  out->pose_covariance = filter_.deadReckonedCovariance(last_odometry_, odometry);
}

void SlamPipeline::anchorAt(double stamp, const Pose2& odometry) {
  last_odometry_ = odometry;
  front_end_.markIteration();
  last_raw_odometry_ = current_raw_odometry_;
  last_stamp_ = stamp;
}

bool SlamPipeline::predict(double stamp, const Pose2& odometry, double dt, ScanResult* out) {
  const bool accept = accept_next_motion_;
  const FilterStatus status = filter_.predict(last_odometry_, odometry, dt, !accept);
  if (status == FilterStatus::kOk) {
    if (accept) {
      accept_next_motion_ = false;
      if (options_.filter.isJump(controlFromOdometry(last_odometry_, odometry))) {
        ++counters_.accepted_large_moves;
      }
    }
    return true;
  }
  const Pose2 motion = between(last_odometry_, odometry);
  std::ostringstream message;
  message << "odometry increment (" << motion.x << " m, " << motion.y << " m, "
          << radToDeg(motion.theta) << " deg) over " << dt << " s refused: " << toString(status);
  if (status == FilterStatus::kOdometryJump) {
    ++counters_.odometry_jumps;
    out->outcome = ScanOutcome::kRejectedOdometryJump;
    message << "; odometry re-anchored, the increment is discarded";
    anchorAt(stamp, odometry);  // later increments start from here
  } else {
    ++counters_.bad_input;
    out->outcome = ScanOutcome::kRejectedBadInput;
  }
  out->message = message.str();
  out->pose = filter_.filter().pose();
  out->pose_covariance = filter_.filter().poseCovariance();
  return false;
}

void SlamPipeline::iterate(double stamp, const Scan* scan, const FeatureSet* features,
                           const Pose2& odometry, bool predict_first, double dt, ScanResult* out) {
  const OdometryControl control = controlFromOdometry(last_odometry_, odometry);
  if (predict_first) {
    if (!predict(stamp, odometry, dt, out)) return;
    const EkfSlam& filter = filter_.filter();
    history_.addTransition(filter.lastMotionJacobian(), filter.pose(), filter.poseCovariance());
  }
  const std::optional<Pose2> local_motion = front_end_.localMotion();
  // The wheels' own step, for the full smoother's wheel edges: only where
  // the control is not the wheels already, and never across a jump.
  const Pose2 wheels = between(last_raw_odometry_, current_raw_odometry_);
  const bool wheels_usable =
      front_end_.matchesScans() && predict_first &&
      !options_.filter.isJump(controlFromOdometry(last_raw_odometry_, current_raw_odometry_));
  anchorAt(stamp, odometry);

  out->features = scan != nullptr ? extractFeatures(*scan, options_.features) : *features;
  filter_.update(out);
  history_.addIteration(stamp, filter_.filter(), predict_first ? &control : nullptr,
                        out->observations, out->iteration, local_motion ? &*local_motion : nullptr,
                        wheels_usable ? &wheels : nullptr);
  ++counters_.iterations;
  filter_.maintain(*out);
  out->outcome = ScanOutcome::kIterated;
  out->pose = filter_.filter().pose();
  out->pose_covariance = filter_.filter().poseCovariance();
}

void SlamPipeline::record(double stamp, const Scan* scan, const Pose2& odometry, bool usable,
                          ScanResult* out) {
  Pose2 causal = out->pose;
  if (back_end_.active() && scan != nullptr) {
    const BackEndLink::Step step =
        back_end_.addScan(stamp, *scan, odometry, usable, out->pose, history_.recordedScans(),
                          observedIds(*out), filter_.filter());
    causal = step.causal;
    if (step.new_loops && options_.loop_closure.reanchor_filter) {
      // The filter takes the loop-closed geometry: the robot moves to the
      // causal estimate, every landmark with the key scan it hangs off.
      const auto corrections = back_end_.reanchorCorrections(filter_.filter());
      filter_.reanchor(compose(causal, inverse(out->pose)), corrections);
      if (out->outcome == ScanOutcome::kIterated) {
        out->pose = filter_.filter().pose();
        out->pose_covariance = filter_.filter().poseCovariance();
      } else {
        deadReckon(odometry, out);
      }
    }
  }
  ScanRecord r;
  r.stamp = stamp;
  r.filtered = out->pose;
  r.covariance = out->pose_covariance;
  r.odometry = odometry;
  r.iteration = history_.currentIteration();
  r.odometry_at_iteration = last_odometry_;
  r.causal = causal;
  out->causal_pose = causal;
  if (history_.add(r, scan) > 0) back_end_.forgetBefore(history_.firstScan(), filter_.filter());
}

std::vector<StampedPose> SlamPipeline::smoothedScanPoses(FullSmootherResult* details,
                                                         LandmarkGraph* last_problem) const {
  return solveSmoothing(history_, filter_.filter(), back_end_.loopConstraints(history_),
                        back_end_.loopClosedIterationPoses(history_), options_.smoother, details,
                        last_problem);
}

SmoothingProblem SlamPipeline::smoothingProblem() const {
  return {history_, filter_.filter(), back_end_.loopConstraints(history_),
          back_end_.loopClosedIterationPoses(history_), options_.smoother};
}

}  // namespace ekf_slam
