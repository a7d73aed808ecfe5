#include "ekf_slam_core/pipeline/state_merge.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "ekf_slam_core/pipeline/back_end_link.h"

namespace ekf_slam {
namespace {

// One saved run, opened for smoothing: its history, its own loops as
// constraints between its iterations, and its finished loop-closed graph
// with what hangs off each key scan.
struct Run {
  explicit Run(const PipelineOptions& options)
      : history(0, options.initial_pose, options.initial_pose_covariance) {}
  ScanHistory history;
  std::vector<IterationConstraint> loops;
  std::vector<Pose2> initial;  // one per iteration: the loop-closed poses, else the filter's
  PoseGraph graph;             // over the key scans, in its own frame
  Pose2 map_from_graph;
  // Per key scan: its iteration (−1: not in the history) and the offset
  // from that iteration's pose.
  std::vector<int> key_iteration;
  std::vector<Pose2> key_offset;
  // Per iteration: a scan of it in the graph (the key scan it hangs off,
  // −1: none) and the offset from that key scan to the iteration's pose.
  std::vector<int> iteration_key;
  std::vector<Pose2> iteration_offset;
};

std::string openRun(const SlamState& state, const PipelineOptions& options, Run* run) {
  if (state.back_end.closer.keys.empty()) return "it holds no key scans (loop closure was off)";
  if (state.history.iterations.empty()) return "it holds no history of the scans";
  if (std::string error = run->history.restore(state.history); !error.empty()) return error;
  PipelineOptions inline_back_end = options;
  inline_back_end.back_end_thread = false;
  inline_back_end.history_scans = 0;
  BackEndLink link(inline_back_end);
  if (std::string error = link.resume(state.back_end, /*same_frame=*/true); !error.empty()) {
    return error;
  }
  link.finish();
  run->loops = link.loopConstraints(run->history);
  run->initial = link.loopClosedIterationPoses(run->history);
  const std::vector<SmootherIteration>& iterations = run->history.smootherRecord().iterations();
  if (run->initial.size() != iterations.size()) {
    // An iteration without a scan in the graph: the filter's poses.
    run->initial.clear();
    for (const SmootherIteration& it : iterations) run->initial.push_back(it.filtered);
  }
  const LoopCloser& closer = *link.loopCloser();
  run->graph = closer.graph();
  run->map_from_graph = state.back_end.map_from_graph;
  const BackEndLinkState& b = state.back_end;
  const long first_loop_scan =
      b.closer.scan_count - static_cast<long>(b.record_of_loop_scan.size());
  const int first_iteration = run->history.firstIteration();
  run->iteration_key.assign(iterations.size(), -1);
  run->iteration_offset.assign(iterations.size(), Pose2());
  for (size_t i = 0; i < b.record_of_loop_scan.size(); ++i) {
    const long scan = first_loop_scan + static_cast<long>(i);
    const ScanRecord* record = run->history.record(b.record_of_loop_scan[i]);
    if (scan < closer.firstScan() || scan >= closer.scanCount() || record == nullptr) continue;
    const int k = record->iteration - first_iteration;
    const int key = closer.scanKey(static_cast<int>(scan));
    if (k < 0 || k >= static_cast<int>(iterations.size()) || key < 0 ||
        run->iteration_key[k] >= 0) {
      continue;
    }
    run->iteration_key[k] = key;
    run->iteration_offset[k] =
        compose(closer.scanOffset(static_cast<int>(scan)),
                inverse(between(record->odometry_at_iteration, record->odometry)));
  }
  const size_t keys = b.closer.keys.size();
  run->key_iteration.assign(keys, -1);
  run->key_offset.assign(keys, Pose2());
  for (size_t k = 0; k < keys; ++k) {
    const long i = b.closer.keys[k].scan_index - first_loop_scan;
    if (i < 0 || i >= static_cast<long>(b.record_of_loop_scan.size())) continue;
    const ScanRecord* record = run->history.record(b.record_of_loop_scan[i]);
    if (record == nullptr || record->iteration < first_iteration) continue;
    run->key_iteration[k] = record->iteration - first_iteration;
    run->key_offset[k] = between(record->odometry_at_iteration, record->odometry);
  }
  return "";
}

// Each iteration's pose from the key scans' (`key_pose`, map frame) where
// one of its scans hangs off a key scan, else `fallback`'s.
void iterationPoses(const Run& run, const std::vector<Pose2>& key_pose,
                    const std::vector<Pose2>& fallback, std::vector<Pose2>* out) {
  for (size_t k = 0; k < run.iteration_key.size(); ++k) {
    const int key = run.iteration_key[k];
    out->push_back(key >= 0 ? compose(key_pose[key], run.iteration_offset[k]) : fallback[k]);
  }
}

// What a frame turned by `theta` does to a pose's covariance and to a
// motion Jacobian: R (·) Rᵀ with this R.
Matrix3 turn(double theta) {
  Matrix3 R = Matrix3::Identity();
  R.topLeftCorner<2, 2>() = Pose2(0.0, 0.0, theta).rotation();
  return R;
}

// The second history after the first: its poses moved by `T`, its
// iterations and records numbered on from the first's, its landmark ids
// shifted by `id_shift`. Its scans before its first iteration are left out.
ScanHistoryState joinHistories(const ScanHistoryState& first, const ScanHistoryState& second,
                               const Pose2& T, int id_shift) {
  ScanHistoryState out = first;
  const Matrix3 R = turn(T.theta);
  const int iteration_shift =
      first.first_iteration + static_cast<int>(first.iterations.size()) - second.first_iteration;
  for (ScanRecord r : second.records) {
    if (r.iteration < second.first_iteration) continue;
    r.iteration += iteration_shift;
    r.filtered = compose(T, r.filtered);
    r.causal = compose(T, r.causal);
    r.covariance = R * r.covariance * R.transpose();
    out.records.push_back(r);
  }
  for (SmootherStep step : second.steps) {
    step.filtered = compose(T, step.filtered);
    step.filtered_cov = R * step.filtered_cov * R.transpose();
    step.predicted_next = compose(T, step.predicted_next);
    step.predicted_next_cov = R * step.predicted_next_cov * R.transpose();
    step.F_next = R * step.F_next * R.transpose();
    out.steps.push_back(step);
  }
  for (SmootherIteration it : second.iterations) {
    it.filtered = compose(T, it.filtered);
    for (LandmarkSighting& s : it.sightings) s.landmark_id += id_shift;
    out.iterations.push_back(std::move(it));
  }
  for (const auto& [from, to] : second.merged_into) {
    out.merged_into.emplace_back(from + id_shift, to + id_shift);
  }
  for (const auto& [id, position] : second.last_estimates) {
    out.last_estimates.emplace_back(id + id_shift, transformFrom(T, position));
  }
  return out;
}

}  // namespace

StateMerge mergeStates(const SlamState& first, const SlamState& second,
                       const PipelineOptions& options, const MergeOptions& merge) {
  StateMerge out;
  Run a(options), b(options);
  if (std::string error = openRun(first, options, &a); !error.empty()) {
    out.error = "the first state: " + error;
    return out;
  }
  if (std::string error = openRun(second, options, &b); !error.empty()) {
    out.error = "the second state: " + error;
    return out;
  }
  const Pose2 mount = between(first.laser_pose, second.laser_pose);
  if (std::hypot(mount.x, mount.y) > 0.01 || std::abs(mount.theta) > 0.5 * kPi / 180.0) {
    out.error = "the two states were made with different laser mounts";
    return out;
  }

  // 1. The second run in the first's map.
  GlobalLocalizer localizer(first, options.scan_matching, merge.alignment);
  if (!localizer.mapError().empty()) {
    out.error = "the first state's map cannot be searched: " + localizer.mapError();
    return out;
  }
  const std::vector<LoopCloserState::Key>& second_keys = second.back_end.closer.keys;
  std::string last_reason = "no key scan with readings";
  for (size_t k = 0; k < second_keys.size(); ++k) {
    if (second_keys[k].points.empty() || b.key_iteration[k] < 0) continue;
    const GlobalPlacement placement =
        localizer.add(second_keys[k].points, second_keys[k].front_end);
    if (!placement.searched) continue;
    ++out.second_keys_tried;
    if (placement.found) {
      out.aligned_key = static_cast<int>(k);
      out.placement = placement;
      out.first_from_second =
          compose(placement.map_pose, inverse(compose(b.map_from_graph, b.graph.pose(k))));
      break;
    }
    last_reason = placement.message;
  }
  if (out.aligned_key < 0) {
    out.error = "no key scan of the second state was found in the first's map (" +
                std::to_string(out.second_keys_tried) + " searches; the last: " + last_reason + ")";
    return out;
  }
  const Pose2& T = out.first_from_second;

  // The two key-scan graphs joined in the first map frame (node 0, the
  // first run's first key scan, stays fixed).
  const std::vector<LoopCloserState::Key>& first_keys = first.back_end.closer.keys;
  const int first_nodes = static_cast<int>(first_keys.size());
  PoseGraph graph;
  for (const Pose2& p : a.graph.poses()) graph.addNode(compose(a.map_from_graph, p));
  for (const Pose2& p : b.graph.poses()) graph.addNode(compose(T, compose(b.map_from_graph, p)));
  for (const PoseGraphEdge& e : a.graph.edges()) graph.addEdge(e);
  for (PoseGraphEdge e : b.graph.edges()) {
    e.from += first_nodes;
    e.to += first_nodes;
    graph.addEdge(e);
  }

  // 2. Loops between the runs, verified as the loop closer verifies them,
  // in rounds: where the runs' own drift put a second-run key scan beyond
  // the window of the place it saw, the joined graph optimised with the
  // loops found so far brings it nearer, and the next round finds it.
  const int first_iterations = static_cast<int>(a.history.smootherRecord().iterations().size());
  std::vector<IterationConstraint> loops = a.loops;
  for (IterationConstraint c : b.loops) {
    c.from_iteration += first_iterations;
    c.to_iteration += first_iterations;
    loops.push_back(c);
  }
  out.first_loops = static_cast<int>(a.loops.size());
  out.second_loops = static_cast<int>(b.loops.size());
  const LoopClosureOptions& lc = options.loop_closure;
  const ScanMatcherOptions& icp = options.scan_matching;
  const Matrix3 loop_information =
      Vector3(1.0 / (lc.loop_sigma_translation * lc.loop_sigma_translation),
              1.0 / (lc.loop_sigma_translation * lc.loop_sigma_translation),
              1.0 / (lc.loop_sigma_rotation * lc.loop_sigma_rotation))
          .asDiagonal();
  LikelihoodGrid grid;  // the verifications' search grid
  // A second-run key scan is placed as well as the nearest joined one
  // along its own chain (the one found by the alignment, or one with a
  // loop to the first run), less the drift over the travel between them:
  // its window is the loop closer's for that travel.
  std::vector<double> travel(second_keys.size(), 0.0);  // along the second run, m
  for (size_t k = 1; k < second_keys.size(); ++k) {
    travel[k] = travel[k - 1] + second_keys[k].travel_from_previous;
  }
  std::vector<char> joined_key(second_keys.size(), 0);
  joined_key[out.aligned_key] = 1;
  // Second-run key scan `kb`, placed at `placed` (first map frame), matched
  // within ±radius, ±angle against the first run's key scans in reach,
  // nearest first: true with the one that verified and the relative pose.
  const auto match = [&](size_t kb, const Pose2& placed, double radius, double angle, int* near,
                         Pose2* relative) {
    std::vector<std::pair<double, int>> candidates;
    for (int ka = 0; ka < first_nodes; ++ka) {
      if (first_keys[ka].points.empty() || a.key_iteration[ka] < 0) continue;
      const Pose2& candidate = graph.pose(ka);
      const double d = (candidate.translation() - placed.translation()).norm();
      if (d <= std::max(radius, merge.loop_radius) &&
          std::abs(wrapAngle(candidate.theta - placed.theta)) <= merge.loop_turn) {
        candidates.emplace_back(d, ka);
      }
    }
    std::sort(candidates.begin(), candidates.end());
    if (static_cast<int>(candidates.size()) > lc.max_candidates) {
      candidates.resize(lc.max_candidates);
    }
    const std::vector<Vector2>& query = second_keys[kb].points;
    const std::vector<Vector2> sparse = gridThinned(query, lc.search_point_spacing);
    for (const auto& [distance, candidate] : candidates) {
      ++out.cross_tried;
      const Pose2& origin = graph.pose(candidate);
      const Pose2 guess = between(origin, placed);
      const KeyRange range = loopSubmapKeys(lc, candidate, first_nodes, guess.theta, [&](int m) {
        return first_keys[m].travel_from_previous;
      });
      std::vector<Vector2> submap;
      for (int m = range.first; m <= range.last; ++m) {
        const Pose2 placement = between(origin, graph.pose(m));
        for (const Vector2& p : first_keys[m].points) submap.push_back(transformFrom(placement, p));
      }
      if (verifyLoop(query, sparse, submap, guess, radius, angle, lc, icp, &grid, relative) ==
          LoopVerdict::kAccepted) {
        *near = candidate;
        return true;
      }
    }
    return false;
  };
  const auto addLoop = [&](int near, size_t kb, const Pose2& relative) {
    PoseGraphEdge edge;
    edge.from = near;
    edge.to = first_nodes + static_cast<int>(kb);
    edge.measurement = relative;
    edge.information = loop_information;
    edge.robust = true;
    graph.addEdge(edge);
    IterationConstraint c;
    c.from_iteration = a.key_iteration[near];
    c.from_offset = a.key_offset[near];
    c.to_iteration = first_iterations + b.key_iteration[kb];
    c.to_offset = b.key_offset[kb];
    c.measurement = relative;
    c.information = loop_information;
    loops.push_back(c);
    joined_key[kb] = 1;
    ++out.cross_loops;
  };
  const auto usable = [&](size_t kb) {
    return !second_keys[kb].points.empty() && b.key_iteration[kb] >= 0;
  };
  for (int round = 0; round < merge.loop_rounds; ++round) {
    const long loops_before = out.cross_loops;
    const std::vector<char> joined_before = joined_key;
    for (size_t kb = 0; kb < second_keys.size(); ++kb) {
      if (joined_key[kb] || !usable(kb)) continue;
      double drift = std::numeric_limits<double>::infinity();
      for (size_t j = 0; j < second_keys.size(); ++j) {
        if (joined_before[j]) drift = std::min(drift, std::abs(travel[kb] - travel[j]));
      }
      const double radius = loopSearchRadius(lc, drift);
      const Pose2& placed = graph.pose(first_nodes + static_cast<int>(kb));
      int near = -1;
      Pose2 relative;
      if (!match(kb, placed, radius, loopSearchAngle(lc, drift), &near, &relative)) continue;
      if (radius <= lc.confirm_radius) {
        addLoop(near, kb, relative);
        continue;
      }
      // Found in a window where a look-alike place could pass: one of the
      // next confirm_keys key scans must match, in the smallest window,
      // where this loop puts it (as the loop closer confirms a hypothesis).
      const Pose2 here = compose(graph.pose(near), relative);
      for (size_t next = kb + 1;
           next < second_keys.size() && next <= kb + static_cast<size_t>(lc.confirm_keys); ++next) {
        if (!usable(next)) continue;
        const Pose2 predicted =
            compose(here, between(graph.pose(first_nodes + static_cast<int>(kb)),
                                  graph.pose(first_nodes + static_cast<int>(next))));
        int near_next = -1;
        Pose2 relative_next;
        if (match(next, predicted, lc.search_radius_min, lc.search_angle_min, &near_next,
                  &relative_next)) {
          addLoop(near, kb, relative);
          if (!joined_key[next]) addLoop(near_next, next, relative_next);
          break;
        }
      }
    }
    ++out.loop_rounds;
    if (out.cross_loops == loops_before) break;
    graph.optimize(lc.optimizer);
  }

  // 3. One problem, started where the joined graph puts each iteration.
  ScanHistory joined(0, options.initial_pose, options.initial_pose_covariance);
  const int id_shift = std::max(first.filter.next_id, 0);
  if (std::string error = joined.restore(joinHistories(first.history, second.history, T, id_shift));
      !error.empty()) {
    out.error = "the joined history: " + error;
    return out;
  }
  const std::vector<Pose2>& nodes = graph.poses();
  std::vector<Pose2> initial;
  iterationPoses(a, std::vector<Pose2>(nodes.begin(), nodes.begin() + first_nodes), a.initial,
                 &initial);
  std::vector<Pose2> second_fallback;
  for (const Pose2& p : b.initial) second_fallback.push_back(compose(T, p));
  iterationPoses(b, std::vector<Pose2>(nodes.begin() + first_nodes, nodes.end()), second_fallback,
                 &initial);
  EkfSlam filter(options.filter);
  filter.restore(first.filter);
  out.first_scans = static_cast<long>(first.history.records.size());
  out.second_scans = joined.recordedScans() - joined.firstScan() - out.first_scans;
  out.problem.emplace(SmoothingProblem{std::move(joined), std::move(filter), std::move(loops),
                                       std::move(initial), options.smoother});
  return out;
}

}  // namespace ekf_slam
