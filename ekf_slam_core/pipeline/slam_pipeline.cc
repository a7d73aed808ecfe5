#include "ekf_slam_core/pipeline/slam_pipeline.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>

#include "ekf_slam_core/mecp/mecp_update.h"

namespace ekf_slam {

const char* toString(ScanOutcome outcome) {
  switch (outcome) {
    case ScanOutcome::kIterated:
      return "iterated";
    case ScanOutcome::kSkippedNoMotion:
      return "skipped (no motion)";
    case ScanOutcome::kSkippedTimeNotIncreasing:
      return "skipped (time not increasing)";
    case ScanOutcome::kRejectedOdometryJump:
      return "rejected (odometry jump)";
    case ScanOutcome::kRejectedBadInput:
      return "rejected (bad input)";
  }
  return "unknown";
}

std::string PipelineOptions::validate() const {
  std::string error = validateFeatureOptions(features);
  if (!error.empty()) return "features: " + error;
  error = filter.validate();
  if (!error.empty()) return "filter: " + error;
  error = association.validate();
  if (!error.empty()) return "association: " + error;
  if (!initial_pose.allFinite() || std::abs(initial_pose.x) > kMaxOdometryCoordinate ||
      std::abs(initial_pose.y) > kMaxOdometryCoordinate) {
    return "initial_pose must be finite and within 1e6 m of the map origin";
  }
  if (!initial_pose_covariance.allFinite() ||
      !initial_pose_covariance.isApprox(initial_pose_covariance.transpose()) ||
      initial_pose_covariance.diagonal().minCoeff() < 0.0) {
    return "initial_pose_covariance must be finite, symmetric, with a non-negative diagonal";
  }
  error = checkFields(*this);
  if (!error.empty()) return error;
  if (min_landmark_range >= max_landmark_range) {
    return "min_landmark_range must be below max_landmark_range (m)";
  }
  error = scan_matching.validate();
  if (!error.empty()) return "scan_matching: " + error;
  error = scan_matched_motion_noise.validate();
  if (!error.empty()) return "scan_matching.motion_noise: " + error;
  error = loop_closure.validate();
  if (!error.empty()) return "loop_closure: " + error;
  error = smoother.validate();
  if (!error.empty()) return "smoother: " + error;
  error = rooms.doorways.validate();
  if (!error.empty()) return "rooms.doorways: " + error;
  error = rooms.map.validate();
  if (!error.empty()) return "rooms.map: " + error;
  if (rooms.enabled && landmarks != LandmarkSet::kPointsAndLines &&
      landmarks != LandmarkSet::kPointsAndLineAngles) {
    return "rooms.enabled needs walls: landmarks points+lines or points+lines_theta";
  }
  if (history_scans < 0) return "history_scans must be >= 0 (0: every scan)";
  return "";
}

MotionNoiseOptions PipelineOptions::defaultScanMatchedMotionNoise() {
  MotionNoiseOptions noise;
  noise.rot_per_rot = 0.0004;      // 2 % of the turn (1 sigma)
  noise.rot_per_trans = 0.0001;    // 0.6 deg per m driven
  noise.trans_per_trans = 0.0004;  // 2 % of the distance
  noise.trans_per_rot = 0.0001;    // 1 cm per rad turned
  noise.min_rot_sigma = 0.002;     // rad (0.11 deg) per step: the matcher's own jitter
  noise.min_trans_sigma = 0.005;   // m per step
  return noise;
}

bool usableOdometry(const Pose2& odometry) {
  return odometry.allFinite() && std::abs(odometry.x) <= kMaxOdometryCoordinate &&
         std::abs(odometry.y) <= kMaxOdometryCoordinate;
}

namespace {
std::unique_ptr<LineLandmarks> lineLandmarksFor(const PipelineOptions& options) {
  switch (options.landmarks) {
    case LandmarkSet::kPoints:
    case LandmarkSet::kPointsAndMecp:
      return nullptr;
    case LandmarkSet::kPointsAndLines:
      return std::make_unique<LineLandmarks>(LandmarkKind::kLine, options.lines,
                                             options.association);
    case LandmarkSet::kPointsAndLineAngles:
      return std::make_unique<LineLandmarks>(LandmarkKind::kLineAngle, options.lines,
                                             options.association);
  }
  return nullptr;
}

// The full smoother's local matcher, when its motion edges need one.
std::unique_ptr<ScanMatchingOdometry> localMatcherFor(const PipelineOptions& options) {
  if (!options.scan_matching.enabled || options.scan_matching.map_mode != "global" ||
      options.smoother.motion_edges != SmootherMotion::kLocalMatch) {
    return nullptr;
  }
  ScanMatcherOptions local = options.scan_matching;
  local.map_mode = "local";
  local.local_map_scans = options.smoother.local_match_key_scans;
  return std::make_unique<ScanMatchingOdometry>(local, options.filter.motion_noise);
}

FilterOptions filterOptionsFor(const PipelineOptions& options) {
  FilterOptions filter = options.filter;
  if (options.scan_matching.enabled) filter.motion_noise = options.scan_matched_motion_noise;
  return filter;
}
}  // namespace

SlamPipeline::SlamPipeline(const PipelineOptions& options)
    : options_(options),
      scan_matcher_(options.scan_matching.enabled
                        ? std::make_unique<ScanMatchingOdometry>(options.scan_matching,
                                                                 options.filter.motion_noise)
                        : nullptr),
      local_matcher_(localMatcherFor(options)),
      // The loop closer keeps its per-scan entries for at least the
      // pipeline's longest history (history_scans plus the trimming step).
      back_end_(options.loop_closure.enabled
                    ? std::make_unique<LoopClosureBackEnd>(
                          options.loop_closure, options.scan_matching, options.back_end_thread,
                          options.history_scans > 0
                              ? options.history_scans + std::max(1L, options.history_scans / 8)
                              : 0)
                    : nullptr),
      lines_(lineLandmarksFor(options)),
      filter_(filterOptionsFor(options), options.initial_pose, options.initial_pose_covariance) {
  full_recorder_.setPrior(options.initial_pose, options.initial_pose_covariance);
  counters_.local_matcher_runs = local_matcher_ != nullptr;
}

Pose2 SlamPipeline::deadReckoned(const Pose2& odometry) const {
  return compose(filter_.pose(), between(last_odometry_, odometry));
}

// The prediction's pose block, F P Fᵀ + G Q Gᵀ, without touching the filter.
Matrix3 SlamPipeline::deadReckonedCovariance(const Pose2& odometry) const {
  const OdometryControl u = controlFromOdometry(last_odometry_, odometry);
  Matrix3 F, G;
  applyControl(filter_.pose(), u, &F, &G);
  const Matrix3 covariance =
      F * filter_.poseCovariance() * F.transpose() +
      G * controlCovariance(u, filter_.options().motion_noise) * G.transpose();
  return 0.5 * (covariance + covariance.transpose());
}

// Against the robot's raw odometry frame (what odom → base_link on tf
// carries), also when the control is scan-matched.
Pose2 SlamPipeline::mapToOdom() const {
  return compose(filter_.pose(), inverse(last_raw_odometry_));
}

ScanResult SlamPipeline::processScan(const Scan& scan, const Pose2& odometry) {
  return process(scan.stamp, &scan, nullptr, odometry);
}

ScanResult SlamPipeline::processFeatures(double stamp, const FeatureSet& features,
                                         const Pose2& odometry) {
  return process(stamp, nullptr, &features, odometry);
}

ScanResult SlamPipeline::process(double stamp, const Scan* scan, const FeatureSet* features,
                                 const Pose2& raw_odometry) {
  ++counters_.scans;
  // Below, `odometry` is the control source's pose: scan-matched or raw.
  Pose2 odometry = raw_odometry;
  current_raw_odometry_ = raw_odometry;
  ScanResult out;
  bool usable = false;
  auto record = [&]() {
    Pose2 causal = out.pose;
    if (back_end_ && scan != nullptr) {
      const int loop_scan = first_loop_scan_ + static_cast<int>(record_of_loop_scan_.size());
      record_of_loop_scan_.push_back(static_cast<int>(recordedScans()));
      pending_filtered_.push_back(out.pose);
      for (int id : out.iteration.new_landmark_ids) landmark_scan_[id] = loop_scan;
      for (int id : out.lines.new_landmark_ids) landmark_scan_[id] = loop_scan;
      view_ = back_end_->addScan(stamp, *scan, options_.filter.laser_pose, odometry, usable);
      const Pose2 graph_pose = view_->poseOf(odometry);
      if (!have_map_from_graph_) {
        map_from_graph_ = compose(out.pose, inverse(graph_pose));
        have_map_from_graph_ = true;
      }
      causal = compose(map_from_graph_, graph_pose);
      trackKeyScans();
      const bool new_loops = view_->counters.accepted != loops_seen_;
      loops_seen_ = view_->counters.accepted;
      if (new_loops && options_.loop_closure.reanchor_filter) {
        reanchorFilter(causal, out.pose);
        const bool iterated = out.outcome == ScanOutcome::kIterated;
        out.pose = iterated ? filter_.pose() : deadReckoned(odometry);
        out.pose_covariance =
            iterated ? filter_.poseCovariance() : deadReckonedCovariance(odometry);
      }
    }
    ScanRecord r;
    r.stamp = stamp;
    r.filtered = out.pose;
    r.covariance = out.pose_covariance;
    r.odometry = odometry;
    r.iteration = first_iteration_ + static_cast<int>(recorder_.steps().size()) - 1;
    r.odometry_at_iteration = last_odometry_;
    r.causal = causal;
    out.causal_pose = causal;
    records_.push_back(r);
    trimHistory();
  };

  std::string input_error;
  if (scan != nullptr) {
    input_error = validateScan(*scan);
  } else if (scan_matcher_) {
    input_error = "features given without their scan, but scan matching (enabled) needs the scan";
  } else if (back_end_) {
    input_error = "features given without their scan, but loop closure (enabled) needs the scan";
  } else {
    input_error = validateFeatureSet(*features);
  }
  usable = usableOdometry(odometry) && input_error.empty() && std::isfinite(stamp);
  if (scan_matcher_ && usableOdometry(odometry)) {
    if (usable) {
      // The filter's jump rule on the raw increment, before it becomes the
      // match's guess: a corrupt sample must not carry the front end (and
      // the key scans of the back end) kilometres away.
      if (!accept_next_motion_ &&
          scan_matcher_->isOdometryJump(raw_odometry, options_.filter.max_step_translation,
                                        options_.filter.max_step_rotation)) {
        scan_matcher_->reanchorRaw(raw_odometry);
        if (local_matcher_) local_matcher_->reanchorRaw(raw_odometry);
        ++counters_.odometry_jumps;
      }
      // Both matchers take the scan's points with the same options
      // (localMatcherFor changes only the map's).
      const std::vector<Vector2> points =
          scanPointsInRobotFrame(*scan, options_.filter.laser_pose, options_.scan_matching);
      if (local_matcher_) {
        local_pose_ = local_matcher_->processPoints(points, scan->stamp, raw_odometry);
      }
      MatchResult match;
      odometry = scan_matcher_->processPoints(points, scan->stamp, raw_odometry, &match);
      counters_.front_end = scan_matcher_->counters();
      if (local_matcher_) counters_.local_matcher = local_matcher_->counters();
      if (match.ok) {
        ++counters_.scan_matches;
      } else {
        ++counters_.scan_match_refusals;
      }
    } else {
      odometry = scan_matcher_->deadReckon(raw_odometry);
      if (local_matcher_) local_pose_ = local_matcher_->deadReckon(raw_odometry);
    }
  }
  if (!usable) {
    ++counters_.bad_input;
    out.outcome = ScanOutcome::kRejectedBadInput;
    out.message = !usableOdometry(odometry) ? "odometry pose is not finite or beyond 1e6 m"
                  : !input_error.empty()    ? input_error
                                            : "scan stamp is not finite";
    if (!usableOdometry(odometry)) {
      out.pose = filter_.pose();
      out.pose_covariance = filter_.poseCovariance();
      out.causal_pose = out.pose;
      return out;  // no usable odometry: nothing to record against
    }
    out.pose = initialised_ ? deadReckoned(odometry) : options_.initial_pose;
    out.pose_covariance =
        initialised_ ? deadReckonedCovariance(odometry) : Matrix3(Matrix3::Zero());
    out.causal_pose = out.pose;
    if (initialised_) record();
    return out;
  }

  if (!initialised_) {
    last_odometry_ = odometry;
    last_raw_odometry_ = raw_odometry;
    last_stamp_ = stamp;
    initialised_ = true;
    iterate(stamp, scan, features, odometry, /*predict=*/false, 0.0, &out);
    record();
    return out;
  }

  const double dt = stamp - last_stamp_;
  if (!(dt > 0.0)) {
    ++counters_.time_not_increasing;
    out.outcome = ScanOutcome::kSkippedTimeNotIncreasing;
    std::ostringstream message;
    message.precision(6);
    message << std::fixed << "scan stamp " << stamp << " is not after the last iteration's "
            << last_stamp_ << " (" << dt << " s): scan not used for an update";
    out.message = message.str();
    out.pose = deadReckoned(odometry);
    out.pose_covariance = deadReckonedCovariance(odometry);
    record();
    return out;
  }

  const Pose2 motion = between(last_odometry_, odometry);
  if ((options_.min_travel_distance > 0.0 || options_.min_travel_angle > 0.0) &&
      std::hypot(motion.x, motion.y) < options_.min_travel_distance &&
      std::abs(motion.theta) < options_.min_travel_angle) {
    ++counters_.skipped_no_motion;
    out.outcome = ScanOutcome::kSkippedNoMotion;
    out.pose = deadReckoned(odometry);
    out.pose_covariance = deadReckonedCovariance(odometry);
    record();
    return out;
  }

  iterate(stamp, scan, features, odometry, /*predict=*/true, dt, &out);
  record();
  return out;
}

void SlamPipeline::iterate(double stamp, const Scan* scan, const FeatureSet* features,
                           const Pose2& odometry, bool predict, double dt, ScanResult* out) {
  const OdometryControl control = controlFromOdometry(last_odometry_, odometry);
  if (predict) {
    const bool accept = accept_next_motion_;
    const FilterStatus status = filter_.predict(last_odometry_, odometry, dt, !accept);
    if (status == FilterStatus::kOk && accept) {
      accept_next_motion_ = false;
      if (options_.filter.isJump(control)) ++counters_.accepted_large_moves;
    }
    if (status != FilterStatus::kOk) {
      const Pose2 motion = between(last_odometry_, odometry);
      std::ostringstream message;
      message << "odometry increment (" << motion.x << " m, " << motion.y << " m, "
              << radToDeg(motion.theta) << " deg) over " << dt
              << " s refused: " << toString(status);
      if (status == FilterStatus::kOdometryJump) {
        ++counters_.odometry_jumps;
        out->outcome = ScanOutcome::kRejectedOdometryJump;
        message << "; odometry re-anchored, the increment is discarded";
        last_odometry_ = odometry;  // re-anchor: later increments start from here
        last_local_pose_ = local_pose_;
        last_raw_odometry_ = current_raw_odometry_;
        last_stamp_ = stamp;
      } else {
        ++counters_.bad_input;
        out->outcome = ScanOutcome::kRejectedBadInput;
      }
      out->message = message.str();
      out->pose = filter_.pose();
      out->pose_covariance = filter_.poseCovariance();
      return;
    }
    recorder_.addTransition(filter_.lastMotionJacobian(), filter_.pose(), filter_.poseCovariance());
  }
  const Pose2 local_motion = between(last_local_pose_, local_pose_);
  // The wheels' own step, for the full smoother's wheel edges: only where
  // the control is not the wheels already, and never across a jump.
  const Pose2 wheels = between(last_raw_odometry_, current_raw_odometry_);
  const bool wheels_usable =
      scan_matcher_ != nullptr && predict &&
      !options_.filter.isJump(controlFromOdometry(last_raw_odometry_, current_raw_odometry_));
  last_odometry_ = odometry;
  last_local_pose_ = local_pose_;
  last_raw_odometry_ = current_raw_odometry_;
  last_stamp_ = stamp;

  out->features = scan != nullptr ? extractFeatures(*scan, options_.features) : *features;
  const std::vector<PointFeature>& points = out->features.points_of_interest;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    const PointFeature& point = points[i];
    if (!point.landmark_candidate || point.range > options_.max_landmark_range ||
        point.range < options_.min_landmark_range) {
      continue;
    }
    PointObservation obs;
    obs.z = {point.range, point.bearing};
    obs.covariance = point.range_bearing_covariance;
    out->observations.push_back(obs);
    out->observation_feature.push_back(i);
  }
  out->iteration.predict_status = FilterStatus::kOk;
  Associator in_rooms;
  if (room_gate_) {
    in_rooms = [this](const EkfSlam& filter, const std::vector<PointObservation>& observations,
                      const AssociationOptions& association) {
      return associateInRooms(filter, observations, association, *room_gate_);
    };
  }
  observe(filter_, options_.association, out->observations, &out->iteration, in_rooms);
  if (options_.rooms.enabled) {
    // New landmarks take the room they were seen from.
    const Vector2 laser = compose(filter_.pose(), options_.filter.laser_pose).translation();
    for (const PointMatch& created : out->iteration.created) {
      const int slot = filter_.slotOf(created.landmark_id);
      if (slot < 0) continue;
      landmark_seen_from_[created.landmark_id] = laser;
      if (room_gate_) {
        room_gate_->labelLandmark(created.landmark_id, filter_.landmarkPosition(slot), laser);
      }
    }
  }
  if (lines_) {
    lines_->observe(filter_, out->features, out->observation_feature, out->iteration, &out->lines);
  }
  if (options_.landmarks == LandmarkSet::kPointsAndMecp) updateMecp(*out);
  recorder_.addFiltered(stamp, filter_.pose(), filter_.poseCovariance());
  full_recorder_.addIteration(stamp, filter_, predict ? &control : nullptr, out->observations,
                              out->iteration, local_matcher_ ? &local_motion : nullptr,
                              wheels_usable ? &wheels : nullptr);

  ++counters_.iterations;
  if (out->iteration.update_status != FilterStatus::kOk) ++counters_.update_failures;
  counters_.observations += static_cast<long>(out->observations.size());
  counters_.matches += static_cast<long>(out->iteration.matches.size());
  counters_.pruned += out->iteration.pruned;
  counters_.pruned_rare += pruneRarelySeen();
  counters_.marginalised += boundLandmarks();
  if (lines_) {
    lines_->synchronise(filter_);
    const LineIterationReport& lines = out->lines;
    counters_.line_observations += static_cast<long>(lines.observations.size());
    counters_.line_matches += static_cast<long>(lines.matches.size());
    counters_.line_endpoint_matches += lines.endpoint_matches;
    counters_.line_ambiguous += lines.ambiguous;
    counters_.new_line_landmarks += static_cast<long>(lines.new_landmark_ids.size());
    counters_.lines_refused += lines.refused;
    if (lines.update_status != FilterStatus::kOk) ++counters_.line_update_failures;
    for (double nis : lines.nis) counters_.line_nis_sum += nis;
  }
  for (const ObservationAssociation& a : out->iteration.association.observations) {
    if (a.decision == AssociationDecision::kAmbiguous) ++counters_.ambiguous;
  }
  counters_.new_landmarks += static_cast<long>(out->iteration.new_landmark_ids.size());
  for (double nis : out->iteration.nis) counters_.nis_sum += nis;
  if (options_.rooms.enabled && ++iterations_since_rooms_ >= options_.rooms.rebuild_interval) {
    rebuildRooms();
  }
  out->outcome = ScanOutcome::kIterated;
  out->pose = filter_.pose();
  out->pose_covariance = filter_.poseCovariance();
}

// The walls mapped so far (the line landmarks' sighted stretches) with
// their doorways make the rooms. The map moves as the filter corrects it,
// so the rooms are drawn afresh and every point landmark is labelled again
// from where it was first seen. A map that cannot be drawn (no walls yet,
// an extent beyond rooms.map.max_cells) leaves the association ungated.
void SlamPipeline::rebuildRooms() {
  iterations_since_rooms_ = 0;
  ++counters_.room_rebuilds;
  for (auto it = landmark_seen_from_.begin(); it != landmark_seen_from_.end();) {
    it = filter_.slotOf(it->first) < 0 ? landmark_seen_from_.erase(it) : std::next(it);
  }
  const std::vector<Segment2> walls = lines_->walls(filter_);
  const std::vector<Doorway> doorways = findDoorways(walls, options_.rooms.doorways);
  RoomMap rooms;
  const std::string error =
      walls.empty() ? "no walls mapped" : rooms.build(walls, doorways, options_.rooms.map);
  if (!error.empty()) {
    room_gate_.reset();
    ++counters_.room_rebuild_failures;
    counters_.rooms = 0;
    counters_.doorways = 0;
    return;
  }
  counters_.rooms = rooms.roomCount();
  counters_.doorways = static_cast<int>(doorways.size());
  room_gate_ = std::make_unique<RoomGate>(std::move(rooms), doorways, options_.rooms.gate);
  for (const auto& [id, seen_from] : landmark_seen_from_) {
    room_gate_->labelLandmark(id, filter_.landmarkPosition(filter_.slotOf(id)), seen_from);
  }
}

int SlamPipeline::pruneRarelySeen() {
  if (options_.prune_min_observations <= 0) return 0;
  std::vector<int> ids;
  for (const LandmarkInfo& info : filter_.landmarks()) {
    if (info.observations < options_.prune_min_observations &&
        filter_.step() - info.created_step >= options_.prune_age_steps) {
      ids.push_back(info.id);
    }
  }
  for (int id : ids) filter_.removeLandmark(id);
  return static_cast<int>(ids.size());
}

int SlamPipeline::boundLandmarks() {
  const int excess = filter_.landmarkCount() - options_.max_landmarks;
  if (options_.max_landmarks <= 0 || excess <= 0) return 0;
  // Least recently matched first; of those, the oldest.
  std::vector<const LandmarkInfo*> order;
  order.reserve(filter_.landmarks().size());
  for (const LandmarkInfo& info : filter_.landmarks()) order.push_back(&info);
  std::partial_sort(order.begin(), order.begin() + excess, order.end(),
                    [](const LandmarkInfo* a, const LandmarkInfo* b) {
                      if (a->last_seen_step != b->last_seen_step)
                        return a->last_seen_step < b->last_seen_step;
                      return a->id < b->id;
                    });
  std::vector<int> ids;
  ids.reserve(excess);
  for (int i = 0; i < excess; ++i) ids.push_back(order[i]->id);
  return filter_.removeLandmarks(ids);
}

// The history beyond history_scans goes an eighth of the bound at a time
// (one erase per many scans instead of one per scan). Nothing here feeds
// the causal estimate: the filter, the front end and the back end's view
// are untouched, and landmark_scan_ loses only landmarks the filter no
// longer holds (ids are never reused).
void SlamPipeline::trimHistory() {
  const long keep = options_.history_scans;
  if (keep <= 0) return;
  const long slack = std::max(1L, keep / 8);
  if (static_cast<long>(records_.size()) < keep + slack) return;
  const long drop = static_cast<long>(records_.size()) - keep;
  records_.erase(records_.begin(), records_.begin() + drop);
  first_record_ += drop;
  size_t loop_scans = 0;
  while (loop_scans < record_of_loop_scan_.size() &&
         record_of_loop_scan_[loop_scans] < first_record_) {
    ++loop_scans;
  }
  record_of_loop_scan_.erase(record_of_loop_scan_.begin(),
                             record_of_loop_scan_.begin() + loop_scans);
  first_loop_scan_ += static_cast<int>(loop_scans);
  // The iterations before the one the oldest kept scan hangs off; the first
  // kept one becomes the smoother's start, with the filter's estimate there.
  const int gone = records_.front().iteration - first_iteration_;
  if (gone > 0 && gone < static_cast<int>(recorder_.steps().size())) {
    const SmootherStep& start = recorder_.steps()[gone];
    full_recorder_.setPrior(start.filtered, start.filtered_cov);
    recorder_.dropFront(gone);
    full_recorder_.dropFront(gone);
    first_iteration_ += gone;
  }
  for (auto it = landmark_scan_.begin(); it != landmark_scan_.end();) {
    it = filter_.slotOf(it->first) < 0 ? landmark_scan_.erase(it) : std::next(it);
  }
}

void SlamPipeline::updateMecp(const ScanResult& result) {
  // Per point observation, the landmark it was matched to or made into,
  // following this scan's merges.
  std::vector<int> ids(result.observations.size(), -1);
  const IterationReport& report = result.iteration;
  for (const PointMatch& m : report.matches) ids[m.observation] = m.landmark_id;
  for (const PointMatch& m : report.created) ids[m.observation] = m.landmark_id;
  for (const auto& [kept, dropped] : report.merged) {
    for (int& id : ids) {
      if (id == dropped) id = kept;
    }
  }
  switch (updateWithMecp(&filter_, result.observations, ids).outcome) {
    case MecpOutcome::kApplied:
      ++counters_.mecp_updates;
      break;
    case MecpOutcome::kNoPolygon:
      ++counters_.mecp_without_polygon;
      break;
    case MecpOutcome::kNearCentre:
    case MecpOutcome::kFilterRefused:
      ++counters_.mecp_skipped;
      break;
  }
}

const std::unordered_map<int, LineSupport>& SlamPipeline::lineSupport() const {
  static const std::unordered_map<int, LineSupport> kNone;
  return lines_ ? lines_->support() : kNone;
}

void SlamPipeline::seedLineSupport(const std::unordered_map<int, LineSupport>& support) {
  if (lines_) lines_->seed(filter_, support);
}

std::vector<StampedPose> SlamPipeline::filteredScanPoses() const {
  std::vector<StampedPose> out;
  out.reserve(records_.size());
  for (const ScanRecord& r : records_) out.push_back({r.stamp, r.filtered});
  return out;
}

// The filter's pose at each key scan the back end reports (its pose when
// that scan was processed, before any re-anchoring at it), so that a loop
// closure can move each landmark with the key scan it hangs off (the newest
// key scan at or before the scan that created it). The back end may report
// a key scan scans after it was taken: the poses wait in pending_filtered_.
void SlamPipeline::trackKeyScans() {
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
// geometry: the robot moves to the causal estimate, and every landmark by
// the transform that takes its key scan from where the filter had it to
// where the graph has it now. Later updates then agree with the closed
// loop instead of pulling the robot back to the drifted map.
void SlamPipeline::reanchorFilter(const Pose2& causal, const Pose2& published) {
  const BackEndView& view = *view_;
  std::vector<Pose2> key_map(key_filtered_.size());
  for (size_t k = 0; k < key_filtered_.size(); ++k) {
    key_map[k] = compose(map_from_graph_, view.key_poses[k]);
  }
  std::vector<std::pair<int, Pose2>> corrections;
  corrections.reserve(filter_.landmarks().size());
  for (const LandmarkInfo& info : filter_.landmarks()) {
    const auto it = landmark_scan_.find(info.id);
    if (it == landmark_scan_.end()) continue;
    const int k = view.keyAtOrBefore(it->second);
    if (k < 0) continue;
    corrections.emplace_back(info.id, compose(key_map[k], inverse(key_filtered_[k])));
  }
  filter_.reanchor(compose(causal, inverse(published)), corrections);
  if (lines_) {
    lines_->reanchor(corrections);
    lines_->synchronise(filter_);
  }
  key_filtered_ = std::move(key_map);
  ++counters_.reanchors;
}

std::vector<SlamPipeline::KeyScan> SlamPipeline::keyScans(bool with_points) const {
  std::vector<KeyScan> out;
  if (!view_ || !have_map_from_graph_) return out;
  const BackEndView& view = *view_;
  out.resize(view.key_poses.size());
  for (size_t k = 0; k < view.key_poses.size(); ++k) {
    out[k].stamp = view.key_stamps[k];
    out[k].pose = compose(map_from_graph_, view.key_poses[k]);
    if (with_points) out[k].points = *view.key_points[k];
  }
  return out;
}

std::vector<StampedPose> SlamPipeline::causalScanPoses() const {
  std::vector<StampedPose> out;
  out.reserve(records_.size());
  for (const ScanRecord& r : records_) out.push_back({r.stamp, r.causal});
  return out;
}

void SlamPipeline::finishLoopClosure() {
  if (back_end_) back_end_->drained().finish();
}

std::vector<StampedPose> SlamPipeline::optimizedScanPoses() const {
  return back_end_ ? back_end_->drained().scanPoses() : std::vector<StampedPose>();
}

std::vector<StampedPose> SlamPipeline::scanPosesFrom(
    const std::vector<Pose2>& iteration_poses) const {
  std::vector<StampedPose> out;
  out.reserve(records_.size());
  for (const ScanRecord& r : records_) {
    const int k = r.iteration - first_iteration_;
    if (r.iteration < 0 || k < 0 || k >= static_cast<int>(iteration_poses.size())) {
      out.push_back({r.stamp, r.filtered});
      continue;
    }
    out.push_back(
        {r.stamp, compose(iteration_poses[k], between(r.odometry_at_iteration, r.odometry))});
  }
  return out;
}

std::vector<StampedPose> SlamPipeline::rtsScanPoses() const {
  std::vector<Pose2> poses;
  for (const SmoothedPose& p : smoothTrajectory(recorder_.steps())) poses.push_back(p.pose);
  return scanPosesFrom(poses);
}

// The back end's loop edges join key scans; a key scan's pose is its
// iteration's pose composed with the odometry since that iteration, so each
// loop becomes a constraint between two iteration poses with those offsets.
// A loop with an end before the kept history (history_scans) is left out.
std::vector<IterationConstraint> SlamPipeline::loopConstraints() const {
  std::vector<IterationConstraint> out;
  if (!back_end_) return out;
  const LoopCloser& closer = back_end_->drained();
  const PoseGraph& graph = closer.graph();
  // The kept record of loop scan `scan`, or null.
  auto recordOf = [this](int scan) -> const ScanRecord* {
    const int i = scan - first_loop_scan_;
    if (scan < 0 || i < 0 || i >= static_cast<int>(record_of_loop_scan_.size())) return nullptr;
    const long r = record_of_loop_scan_[i] - first_record_;
    return r >= 0 ? &records_[r] : nullptr;
  };
  for (const PoseGraphEdge& edge : graph.edges()) {
    if (!edge.robust || !edge.active) continue;  // sequential edge, or a dropped loop
    const ScanRecord* from = recordOf(closer.keyScanIndex(edge.from));
    const ScanRecord* to = recordOf(closer.keyScanIndex(edge.to));
    if (from == nullptr || to == nullptr) continue;
    const ScanRecord& a = *from;
    const ScanRecord& b = *to;
    if (a.iteration < first_iteration_ || b.iteration < first_iteration_) continue;
    IterationConstraint c;
    c.from_iteration = a.iteration - first_iteration_;
    c.to_iteration = b.iteration - first_iteration_;
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
std::vector<Pose2> SlamPipeline::loopClosedIterationPoses() const {
  std::vector<Pose2> out;
  if (!back_end_ || records_.empty()) return out;
  const LoopCloser& closer = back_end_->drained();
  // One pose per loop scan the closer still holds (closer.firstScan() on).
  const std::vector<StampedPose> optimized = closer.scanPoses();
  std::vector<int> loop_scan_of_record(records_.size(), -1);
  for (size_t i = 0; i < record_of_loop_scan_.size(); ++i) {
    const long scan = first_loop_scan_ + static_cast<long>(i) - closer.firstScan();
    const long record = record_of_loop_scan_[i] - first_record_;
    if (scan < 0 || record < 0) continue;
    if (scan >= static_cast<long>(optimized.size())) break;
    loop_scan_of_record[record] = static_cast<int>(scan);
  }
  const int iterations = static_cast<int>(full_recorder_.iterations().size());
  out.assign(iterations, Pose2());
  std::vector<char> found(iterations, 0);
  // The whole run: the first scan's filtered pose ties the graph to the map
  // frame. A bounded history has lost that scan: the frame is the one the
  // key scans are given in (keyScans()), so the window and the older key
  // scans agree.
  bool have_frame = first_record_ > 0 && have_map_from_graph_;
  Pose2 map_from_graph = map_from_graph_;
  for (size_t r = 0; r < records_.size(); ++r) {
    const ScanRecord& record = records_[r];
    const int scan = loop_scan_of_record[r];
    if (scan < 0) continue;
    if (!have_frame) {
      // The record's own pose in the map frame, hung off its iteration.
      const Pose2 filtered = record.filtered;
      map_from_graph = compose(filtered, inverse(optimized[scan].pose));
      have_frame = true;
    }
    const int k = record.iteration - first_iteration_;
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

std::vector<StampedPose> SlamPipeline::smoothedScanPoses(FullSmootherResult* details,
                                                         LandmarkGraph* last_problem) const {
  const std::vector<Pose2> initial = loopClosedIterationPoses();
  FullSmootherResult result;
  if (first_iteration_ > 0 && !initial.empty()) {
    // A bounded history starts at its oldest iteration: anchored where the
    // loop-closed graph has it (the frame of the older key scans), as
    // uncertain as the filter was there.
    FullSmootherRecorder window = full_recorder_;
    window.setPrior(initial.front(), full_recorder_.priorCovariance());
    result =
        smoothFull(window, filter_, loopConstraints(), options_.smoother, &initial, last_problem);
  } else {
    result = smoothFull(full_recorder_, filter_, loopConstraints(), options_.smoother,
                        initial.empty() ? nullptr : &initial, last_problem);
  }
  std::vector<StampedPose> out = scanPosesFrom(result.poses);
  if (details) *details = std::move(result);
  return out;
}

}  // namespace ekf_slam
