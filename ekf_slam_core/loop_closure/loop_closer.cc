#include "ekf_slam_core/loop_closure/loop_closer.h"

#include "ekf_slam_core/filter/chi_square.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <unordered_set>

namespace ekf_slam {

std::string LoopClosureOptions::validate() const {
  const std::string error = checkFields(*this);
  if (!error.empty()) return error;
  if (search_radius_max < search_radius_min) {
    return "search_radius_max must be >= search_radius_min (m)";
  }
  return "";
}

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<Vector2> thinned(const std::vector<Vector2>& points, double spacing) {
  std::vector<Vector2> out;
  for (const Vector2& p : points) {
    if (out.empty() || (p - out.back()).norm() >= spacing) out.push_back(p);
  }
  return out;
}

Matrix3 diagonalInformation(double sigma_translation, double sigma_rotation) {
  const double it = 1.0 / (sigma_translation * sigma_translation);
  return Vector3(it, it, 1.0 / (sigma_rotation * sigma_rotation)).asDiagonal();
}

// Covariance of an ICP pose from its point-to-line pairs at the final pose
// (the inverse of Σ J Jᵀ / σ_p², the Gauss-Newton information). It is
// optimistic — the pairs' errors are correlated — but its shape says
// whether the scan constrains every direction.
Matrix3 icpCovariance(const std::vector<Vector2>& points, const PointCloudReference& reference,
                      const Pose2& pose, const ScanMatcherOptions& options) {
  Matrix3 information = Matrix3::Zero();
  const Matrix2 R = pose.rotation();
  for (const Vector2& p : points) {
    const Vector2 rotated = R * p;
    const Vector2 q = rotated + pose.translation();
    const int j = reference.nearest(q, options.correspondence_distance);
    if (j < 0) continue;
    const Vector2& n = reference.normals()[j];
    const Vector3 J(n.x(), n.y(), -n.x() * rotated.y() + n.y() * rotated.x());
    information += J * J.transpose();
  }
  information /= options.point_sigma * options.point_sigma;
  // A tiny regulariser keeps an unconstrained direction finite (and huge).
  information += 1e-9 * Matrix3::Identity();
  return information.inverse();
}

}  // namespace

double explainedStructure(const std::vector<Vector2>& query, const PointCloudReference& reference,
                          const Pose2& pose, const Vector2& direction,
                          const ScanMatcherOptions& options) {
  const PointCloudReference own(query, options.normal_radius, options.correspondence_distance);
  const Matrix2 R = pose.rotation();
  double all = 0.0, explained = 0.0;
  for (size_t i = 0; i < own.size(); ++i) {
    const double along = (R * own.normals()[i]).dot(direction);
    all += along * along;
    if (reference.nearest(transformFrom(pose, own.points()[i]), options.correspondence_distance) >=
        0) {
      explained += along * along;
    }
  }
  return all < 1.0 ? 1.0 : explained / all;
}

double wallDirection(const std::vector<Vector2>& points, const ScanMatcherOptions& options,
                     double* concentration, int* normals) {
  if (concentration) *concentration = 0.0;
  if (normals) *normals = 0;
  if (points.empty()) return 0.0;
  const PointCloudReference cloud(points, options.normal_radius,
                                  options.initial_correspondence_distance);
  // A wall's normal n and the wall itself are a quarter turn apart, and
  // perpendicular walls a quarter turn again: all agree on 4 angle(n).
  double c = 0.0, s = 0.0;
  for (const Vector2& n : cloud.normals()) {
    const double a = 4.0 * std::atan2(n.y(), n.x());
    c += std::cos(a);
    s += std::sin(a);
  }
  const int count = static_cast<int>(cloud.normals().size());
  if (normals) *normals = count;
  if (count == 0) return 0.0;
  if (concentration) *concentration = std::hypot(c, s) / count;
  const double direction = std::atan2(s, c) / 4.0;  // in [−45°, 45°]
  return direction >= kPi / 4.0 ? direction - kPi / 2.0 : direction;
}

namespace {

// `a` modulo a quarter turn, in [−45°, 45°).
double wrapQuarter(double a) {
  constexpr double kQuarter = kPi / 2.0;
  return a - kQuarter * std::floor(a / kQuarter + 0.5);
}

}  // namespace

LoopCloser::LoopCloser(const LoopClosureOptions& options, const ScanMatcherOptions& matcher,
                       long scan_history)
    : options_(options), icp_(matcher), scan_history_(std::max(0L, scan_history)) {
  icp_.max_range = options.max_range;
  // The loop's pose comes from the correlative search, not from odometry:
  // the ICP prior only regularises, it must not pull.
  icp_.prior_sigma_translation = 1.0;
  icp_.prior_sigma_rotation = 0.5;
  icp_.initial_correspondence_distance =
      std::max(icp_.correspondence_distance, 4.0 * options.correlative.resolution);
}

void LoopCloser::addScan(double stamp, const Scan& scan, const Pose2& laser_pose,
                         const Pose2& front_end, bool usable) {
  if (keys_.empty() && usable) {
    addKeyScan(stamp, scanPointsInRobotFrame(scan, laser_pose, icp_), front_end);
  } else if (usable) {
    const Pose2 since = between(keys_.back().front_end, front_end);
    if (std::hypot(since.x, since.y) >= options_.keyscan_distance ||
        std::abs(since.theta) >= options_.keyscan_angle) {
      addKeyScan(stamp, scanPointsInRobotFrame(scan, laser_pose, icp_), front_end);
    }
  }
  ScanEntry entry{stamp, static_cast<int>(keys_.size()) - 1, front_end};
  if (entry.key >= 0) entry.offset = between(keys_[entry.key].front_end, front_end);
  scans_.push_back(entry);
  // The per-scan entries serve scanPoses() alone: with a history bound the
  // oldest go, an eighth of the bound at a time (one erase per many scans).
  const long slack = std::max(1L, scan_history_ / 8);
  if (scan_history_ > 0 && static_cast<long>(scans_.size()) >= scan_history_ + slack) {
    const long drop = static_cast<long>(scans_.size()) - scan_history_;
    scans_.erase(scans_.begin(), scans_.begin() + drop);
    first_scan_ += static_cast<int>(drop);
  }
}

void LoopCloser::addKeyScan(double stamp, const std::vector<Vector2>& points,
                            const Pose2& front_end) {
  KeyScan key;
  key.front_end = front_end;
  if (options_.enabled && options_.heading_radius > 0.0) {
    double concentration = 0.0;
    int normals = 0;
    const double direction = wallDirection(points, icp_, &concentration, &normals);
    if (normals >= options_.heading_min_normals &&
        concentration >= options_.heading_min_concentration) {
      key.wall_direction = direction;
    }
  }
  key.points = std::make_shared<const std::vector<Vector2>>(points);
  key.sparse = thinned(points, options_.search_point_spacing);
  key.scan_index = scanCount();  // its ScanEntry is pushed next
  key.stamp = stamp;
  ++counters_.key_scans;
  adjacency_.emplace_back();
  distances_from_ = -1;
  if (keys_.empty()) {
    graph_.addNode(front_end);
    keys_.push_back(std::move(key));
    return;
  }
  const int previous = static_cast<int>(keys_.size()) - 1;
  const Pose2 step = between(keys_[previous].front_end, front_end);
  const double distance = std::hypot(step.x, step.y);
  key.travel_from_previous = distance;
  const int index = graph_.addNode(compose(graph_.pose(previous), step));
  keys_.push_back(std::move(key));

  // Random walk: variances linear in the distance and the turn.
  const double var_t = options_.step_sigma_translation * options_.step_sigma_translation +
                       std::pow(options_.translation_sigma_per_sqrt_metre, 2) * distance;
  const double var_r = options_.step_sigma_rotation * options_.step_sigma_rotation +
                       std::pow(options_.rotation_sigma_per_sqrt_metre, 2) * distance +
                       std::pow(options_.rotation_sigma_per_sqrt_radian, 2) * std::abs(step.theta);
  PoseGraphEdge edge;
  edge.from = previous;
  edge.to = index;
  edge.measurement = step;
  edge.information = Vector3(1.0 / var_t, 1.0 / var_t, 1.0 / var_r).asDiagonal();
  graph_.addEdge(edge);
  adjacency_[previous].emplace_back(index, distance);
  adjacency_[index].emplace_back(previous, distance);
  distances_from_ = -1;

  if (!options_.enabled) return;
  const long loops = counters_.accepted;
  searchLoops(index);
  // That optimisation took the heading edges so far in.
  if (counters_.accepted != loops) heading_loops_since_optimisation_ = 0;
  if (options_.heading_radius > 0.0) addHeadingLoop(index);
  releaseIfPlaceIsFull(index);
}

void LoopCloser::addHeadingLoop(int key) {
  const double direction = keys_[key].wall_direction;
  if (std::isnan(direction) || hypothesis_) return;  // no walls; or its pose is in doubt
  const Pose2& here = graph_.pose(key);
  const std::vector<double> distance = graphDistances(key);
  int nearest = -1;
  double best = options_.heading_radius;
  for (int j = 0; j < key; ++j) {
    if (std::isnan(keys_[j].wall_direction) || distance[j] < options_.min_loop_travel) continue;
    const double d = std::hypot(graph_.pose(j).x - here.x, graph_.pose(j).y - here.y);
    if (d <= best) {
      best = d;
      nearest = j;
    }
  }
  if (nearest < 0) return;
  // The chain's heading window for this graph distance, widened by the two
  // wall directions' noise (3 sigma each way).
  const double window =
      std::hypot(loopSearchAngle(options_, distance[nearest]),
                 options_.search_sigmas * std::sqrt(2.0) * options_.heading_sigma);
  if (window >= kPi / 4.0) return;  // which quarter turn would be a guess
  const double estimate = wrapAngle(here.theta - graph_.pose(nearest).theta);
  const double residual = wrapQuarter(estimate + direction - keys_[nearest].wall_direction);
  if (std::abs(residual) > window) return;
  PoseGraphEdge edge;
  edge.from = nearest;
  edge.to = key;
  edge.measurement = Pose2(0.0, 0.0, wrapAngle(estimate - residual));
  const double variance = 2.0 * options_.heading_sigma * options_.heading_sigma;
  edge.information = Vector3(0.0, 0.0, 1.0 / variance).asDiagonal();
  edge.robust = true;
  heading_edges_.insert(graph_.addEdge(edge));
  ++counters_.heading_loops;
  if (++heading_loops_since_optimisation_ >= options_.heading_reoptimise) {
    optimise();
    heading_loops_since_optimisation_ = 0;
  }
}

void LoopCloser::searchLoops(int index) {
  if (hypothesis_) {
    if (tryConfirm(index) || hypothesis_) return;  // confirmed, or still waiting
  }
  const std::vector<double> distances = graphDistances(index);
  const std::vector<int> candidates = pickCandidates(index, distances);
  for (const int candidate : candidates) {
    ++counters_.candidates;
    const double radius = loopSearchRadius(options_, distances[candidate]);
    const Pose2 guess = between(graph_.pose(candidate), graph_.pose(index));
    Pose2 relative;
    if (!verify(candidate, index, guess, radius, loopSearchAngle(options_, distances[candidate]),
                &relative)) {
      ++counters_.refused;
      continue;
    }
    if (radius > options_.confirm_radius) {
      hypothesis_ = Hypothesis{candidate, index, relative};
      return;
    }
    if (addLoopEdge(candidate, index, relative)) return;
    break;  // inconsistent with the graph: the others are no likelier
  }
  if (!candidates.empty()) next_attempt_ = index + options_.retry_interval;
}

void LoopCloser::releaseIfPlaceIsFull(int key) {
  // While a wide-window loop awaits confirmation the new key scan's pose is
  // the drifted one: its place is not known yet.
  if (options_.max_keyscans_per_place <= 0 || hypothesis_) return;
  const Pose2& here = graph_.pose(key);
  int held = 0;
  for (int j = 0; j < key && held < options_.max_keyscans_per_place; ++j) {
    const Pose2& there = graph_.pose(j);
    if (hasReadings(j) && std::hypot(there.x - here.x, there.y - here.y) <= options_.place_radius &&
        std::abs(wrapAngle(there.theta - here.theta)) <= options_.place_angle) {
      ++held;
    }
  }
  if (held < options_.max_keyscans_per_place) return;
  keys_[key].points = std::make_shared<const std::vector<Vector2>>();
  keys_[key].sparse = std::vector<Vector2>();
  ++counters_.released;
}

bool LoopCloser::tryConfirm(int key) {
  const Hypothesis h = *hypothesis_;
  if (key - h.to > options_.confirm_keys) {
    hypothesis_.reset();
    ++counters_.unconfirmed;
    return false;
  }
  // Where the hypothesis puts this key scan, in the map frame: the front
  // end's short chain since the hypothesis, hung off the old key scan.
  const Pose2 predicted = compose(
      graph_.pose(h.from), compose(h.relative, between(graph_.pose(h.to), graph_.pose(key))));
  const std::vector<double> distance = graphDistances(key);
  int nearest = -1;
  double best = std::numeric_limits<double>::infinity();
  for (int j = 0; j < key; ++j) {
    if (distance[j] < options_.min_loop_travel || !hasReadings(j)) continue;
    const double d = std::hypot(graph_.pose(j).x - predicted.x, graph_.pose(j).y - predicted.y);
    if (d < best) {
      best = d;
      nearest = j;
    }
  }
  if (nearest < 0) return false;
  ++counters_.candidates;
  Pose2 relative;
  if (!verify(nearest, key, between(graph_.pose(nearest), predicted), options_.search_radius_min,
              options_.search_angle_min, &relative)) {
    ++counters_.refused;
    return false;
  }
  hypothesis_.reset();
  if (addLoopEdge(h.from, h.to, h.relative)) {
    addLoopEdge(nearest, key, relative);
  }
  return true;
}

bool LoopCloser::addLoop(int from, int to, const Pose2& relative) {
  const int keys = static_cast<int>(keys_.size());
  if (from < 0 || to < 0 || from >= keys || to >= keys || from == to || !relative.allFinite()) {
    return false;
  }
  return addLoopEdge(from, to, relative);
}

bool LoopCloser::addLoopEdge(int from, int to, const Pose2& relative) {
  PoseGraphEdge loop;
  loop.from = from;
  loop.to = to;
  loop.measurement = relative;
  loop.information =
      diagonalInformation(options_.loop_sigma_translation, options_.loop_sigma_rotation);
  // Enters at full weight (it passed the scan evidence); the kernel judges
  // it in later optimisations, against the loops that follow.
  loop.robust = false;
  const std::vector<Pose2> before = graph_.poses();
  const int edge_index = graph_.addEdge(loop);
  const double loop_chi2 = graph_.edgeChi2(edge_index);
  const PoseGraphSummary summary = optimise();
  if (options_.consistency_probability > 0.0) {
    // The graph's cost without the loop, at the poses before this
    // optimisation, against its optimised cost with it.
    const double rise = summary.final_cost - (summary.initial_cost - loop_chi2);
    if (rise > chiSquareQuantile(options_.consistency_probability, 3.0)) {
      graph_.setEdgeActive(edge_index, false);
      for (int n = 0; n < static_cast<int>(before.size()); ++n) graph_.setPose(n, before[n]);
      ++counters_.inconsistent;
      return false;
    }
  }
  ++counters_.accepted;
  adjacency_[from].emplace_back(to, 0.0);
  adjacency_[to].emplace_back(from, 0.0);
  distances_from_ = -1;
  graph_.setEdgeRobust(edge_index, true);
  return true;
}

// Dijkstra from `from`: travel along sequential edges, zero across loops.
std::vector<double> LoopCloser::graphDistances(int from) const {
  if (from == distances_from_) return distances_;
  std::vector<double> distance(keys_.size(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  distance[from] = 0.0;
  queue.emplace(0.0, from);
  while (!queue.empty()) {
    const auto [d, node] = queue.top();
    queue.pop();
    if (d > distance[node]) continue;
    for (const auto& [next, length] : adjacency_[node]) {
      if (d + length < distance[next]) {
        distance[next] = d + length;
        queue.emplace(distance[next], next);
      }
    }
  }
  distances_from_ = from;
  distances_ = distance;
  return distance;
}

// Relative pose over a chain of d metres of sequential edges: the heading
// variance grows as σ_r² d, and a heading error that grew linearly along the
// way displaces the far end by its integral, variance σ_r² d³ / 3, on top of
// the translation random walk σ_t² d.
double loopSearchRadius(const LoopClosureOptions& options, double graph_distance) {
  const double d = graph_distance;
  const double var_r = std::pow(options.rotation_sigma_per_sqrt_metre, 2);
  const double var_t = std::pow(options.translation_sigma_per_sqrt_metre, 2);
  const double sigma = std::sqrt(var_t * d + var_r * d * d * d / 3.0);
  return std::clamp(options.search_sigmas * sigma, options.search_radius_min,
                    options.search_radius_max);
}

double loopSearchAngle(const LoopClosureOptions& options, double graph_distance) {
  const double sigma = options.rotation_sigma_per_sqrt_metre * std::sqrt(graph_distance);
  return std::clamp(options.search_sigmas * sigma, options.search_angle_min, kPi);
}

std::vector<int> LoopCloser::pickCandidates(int key, const std::vector<double>& distance) const {
  if (key < next_attempt_) return {};
  const Pose2& here = graph_.pose(key);
  // Ratio of the distance to the window: a near, well-known place first.
  std::vector<std::pair<double, int>> ranked;
  for (int j = 0; j < key; ++j) {
    if (distance[j] < options_.min_loop_travel || !hasReadings(j)) continue;
    const Pose2& there = graph_.pose(j);
    if (std::abs(wrapAngle(there.theta - here.theta)) > options_.max_heading_difference) continue;
    const double ratio =
        std::hypot(there.x - here.x, there.y - here.y) / loopSearchRadius(options_, distance[j]);
    if (ratio <= 1.0) ranked.emplace_back(ratio, j);
  }
  std::sort(ranked.begin(), ranked.end());
  // One per submap: a candidate whose submap overlaps a chosen one's adds nothing.
  std::vector<int> chosen;
  for (const auto& [ratio, j] : ranked) {
    if (static_cast<int>(chosen.size()) >= options_.max_candidates) break;
    bool overlaps = false;
    for (const int c : chosen) overlaps |= std::abs(c - j) <= 2 * options_.submap_half_width;
    if (!overlaps) chosen.push_back(j);
  }
  return chosen;
}

std::vector<Vector2> LoopCloser::queryPoints(int key, bool sparse) const {
  if (options_.query_keys == 0) return sparse ? keys_[key].sparse : *keys_[key].points;
  const Pose2& origin = graph_.pose(key);
  std::vector<Vector2> merged;
  for (int m = key; m >= std::max(0, key - options_.query_keys); --m) {
    const Pose2 placement = between(origin, graph_.pose(m));
    for (const Vector2& p : *keys_[m].points) merged.push_back(transformFrom(placement, p));
  }
  return gridThinned(merged, sparse ? options_.search_point_spacing : icp_.min_point_spacing);
}

KeyRange loopSubmapKeys(const LoopClosureOptions& options, int candidate, int key_count,
                        double guess_heading,
                        const std::function<double(int)>& travel_from_previous) {
  KeyRange range;
  range.first = std::max(0, candidate - options.submap_half_width);
  range.last = std::min(key_count - 1, candidate + options.submap_half_width);
  if (std::abs(wrapAngle(guess_heading)) > kPi / 2.0) {
    double travel = 0.0;
    for (int m = candidate; m > 0 && travel < options.reverse_submap_travel; --m) {
      travel += travel_from_previous(m);
      range.first = std::min(range.first, m - 1);
    }
  }
  return range;
}

LoopVerdict verifyLoop(const std::vector<Vector2>& query, const std::vector<Vector2>& sparse_query,
                       const std::vector<Vector2>& submap, const Pose2& guess, double radius,
                       double angle, const LoopClosureOptions& options,
                       const ScanMatcherOptions& icp, LikelihoodGrid* grid, Pose2* relative) {
  grid->build(submap, options.correlative);
  const CorrelativeResult coarse = correlativeSearch(sparse_query, *grid, guess, radius, angle,
                                                     options.correlative, options.min_score);
  if (coarse.score < options.min_score) return LoopVerdict::kRefusedByScore;

  const PointCloudReference reference(submap, icp.normal_radius,
                                      icp.initial_correspondence_distance);
  const MatchResult fine = matchPoints(query, reference, coarse.pose, icp);
  if (!fine.ok || fine.inlier_fraction < options.min_inlier_fraction ||
      fine.rms_residual > options.max_rms_residual) {
    return LoopVerdict::kRefusedByFit;
  }
  const Pose2 shift = between(coarse.pose, fine.pose);
  if (std::hypot(shift.x, shift.y) > options.max_icp_shift) return LoopVerdict::kRefusedByFit;
  // Along a featureless corridor the match slides: refuse it.
  const Matrix3 covariance = icpCovariance(query, reference, fine.pose, icp);
  const Eigen::SelfAdjointEigenSolver<Matrix2> eigen(covariance.topLeftCorner<2, 2>());
  if (std::sqrt(eigen.eigenvalues()(1)) > options.max_degenerate_sigma) {
    return LoopVerdict::kDegenerate;
  }
  // Where the query itself has structure along the weakest direction (a
  // wall across a corridor), the match must explain it there too, not only
  // on average: a view down one corridor matched onto a view along another
  // shares only the walls parallel to both, and a door frame or two would
  // pass the test above.
  if (explainedStructure(query, reference, fine.pose, eigen.eigenvectors().col(1), icp) <
      options.min_directional_inlier_fraction) {
    return LoopVerdict::kDegenerate;
  }
  // Last, as the dearest: no other place of the window may match nearly as
  // well (the search above returns only the best pose).
  if (options.max_runner_up_ratio < 1.0) {
    const CorrelativeResult rival = correlativeRunnerUp(
        sparse_query, *grid, guess, radius, angle, options.correlative, coarse.pose,
        options.distinct_radius, options.max_runner_up_ratio * coarse.score);
    if (rival.score > 0.0) return LoopVerdict::kAmbiguous;
  }
  *relative = fine.pose;
  return LoopVerdict::kAccepted;
}

bool LoopCloser::verify(int candidate, int key, const Pose2& guess, double radius, double angle,
                        Pose2* relative) {
  const auto start = std::chrono::steady_clock::now();
  struct Timer {
    double* total;
    std::chrono::steady_clock::time_point start;
    ~Timer() { *total += secondsSince(start); }
  } timer{&counters_.verification_seconds, start};

  // The candidate's neighbourhood in its own frame, from the graph poses
  // (locally consistent). Recent key scans are left out: matching them
  // would only repeat the front end.
  const Pose2& origin = graph_.pose(candidate);
  const KeyRange range =
      loopSubmapKeys(options_, candidate, static_cast<int>(keys_.size()), guess.theta,
                     [this](int m) { return keys_[m].travel_from_previous; });
  std::vector<Vector2> submap;
  for (int m = range.first; m <= range.last; ++m) {
    const Pose2 placement = between(origin, graph_.pose(m));
    for (const Vector2& p : *keys_[m].points) submap.push_back(transformFrom(placement, p));
  }
  const std::vector<Vector2> query = queryPoints(key, false);
  if (static_cast<int>(query.size()) < icp_.min_correspondences) {
    ++counters_.refused_by_score;  // nothing to score
    return false;
  }
  // One grid's storage serves every verification; an outsized one (a
  // submap stretched by a corrupt pose) is handed back when it is done.
  struct Bound {
    LikelihoodGrid& grid;
    ~Bound() {
      if (grid.storageBytes() > kKeptGridBytes) grid.release();
    }
  } bound{verify_grid_};
  switch (verifyLoop(query, queryPoints(key, true), submap, guess, radius, angle, options_, icp_,
                     &verify_grid_, relative)) {
    case LoopVerdict::kAccepted:
      return true;
    case LoopVerdict::kRefusedByScore:
      ++counters_.refused_by_score;
      return false;
    case LoopVerdict::kRefusedByFit:
      ++counters_.refused_by_fit;
      return false;
    case LoopVerdict::kDegenerate:
      ++counters_.refused_as_degenerate;
      return false;
    case LoopVerdict::kAmbiguous:
      ++counters_.ambiguous;
      return false;
  }
  return false;
}

PoseGraphSummary LoopCloser::optimise() {
  const auto start = std::chrono::steady_clock::now();
  const PoseGraphSummary summary = graph_.optimize(options_.optimizer);
  ++counters_.optimisations;
  counters_.optimisation_seconds += secondsSince(start);
  return summary;
}

void LoopCloser::finish() {
  verify_grid_.release();  // no more searches
  if (hypothesis_) {
    hypothesis_.reset();
    ++counters_.unconfirmed;
  }
  if (counters_.accepted == 0 && counters_.heading_loops == 0) return;
  final_problem_ = graph_;
  optimise();
  // Loops the kernel no longer believes are dropped, and the rest re-solved
  // without them.
  long dropped = 0;
  for (int e = 0; e < static_cast<int>(graph_.edges().size()); ++e) {
    const PoseGraphEdge& edge = graph_.edges()[e];
    // Loops only: a heading edge the kernel doubts keeps its small weight.
    if (!edge.robust || !edge.active || heading_edges_.count(e) > 0) continue;
    if (graph_.edgeWeight(e, options_.optimizer.robust_kernel_width) < options_.min_final_weight) {
      graph_.setEdgeActive(e, false);
      ++dropped;
    }
  }
  counters_.dropped += dropped;
  if (dropped > 0) {
    final_problem_ = graph_;
    optimise();
  }
}

LoopCloserState LoopCloser::state() const {
  LoopCloserState out;
  out.keys.reserve(keys_.size());
  for (const KeyScan& key : keys_) {
    LoopCloserState::Key k;
    k.front_end = key.front_end;
    k.points = *key.points;
    k.travel_from_previous = key.travel_from_previous;
    k.retry_after = key.retry_after;
    k.scan_index = key.scan_index;
    k.stamp = key.stamp;
    k.wall_direction = key.wall_direction;
    out.keys.push_back(std::move(k));
  }
  out.scans = scans_;
  out.graph = graph_;
  out.adjacency = adjacency_;
  out.heading_edges.assign(heading_edges_.begin(), heading_edges_.end());
  std::sort(out.heading_edges.begin(), out.heading_edges.end());
  out.counters = counters_;
  out.scan_count = scanCount();
  out.next_attempt = next_attempt_;
  out.heading_loops_since_optimisation = heading_loops_since_optimisation_;
  if (hypothesis_) {
    out.has_hypothesis = true;
    out.hypothesis_from = hypothesis_->from;
    out.hypothesis_to = hypothesis_->to;
    out.hypothesis_relative = hypothesis_->relative;
  }
  return out;
}

std::string LoopCloser::resume(const LoopCloserState& state) {
  const int keys = static_cast<int>(state.keys.size());
  const auto is_key = [keys](int k) { return k >= 0 && k < keys; };
  if (state.graph.nodeCount() != keys) {
    return "the graph has " + std::to_string(state.graph.nodeCount()) + " nodes for " +
           std::to_string(keys) + " key scans";
  }
  if (static_cast<int>(state.adjacency.size()) != keys) {
    return "the graph distances list " + std::to_string(state.adjacency.size()) +
           " key scans, not " + std::to_string(keys);
  }
  for (const PoseGraphEdge& edge : state.graph.edges()) {
    if (!is_key(edge.from) || !is_key(edge.to)) return "a graph edge joins a missing key scan";
  }
  for (const auto& neighbours : state.adjacency) {
    for (const auto& [next, travel] : neighbours) {
      if (!is_key(next) || !(travel >= 0.0)) return "a graph distance names a missing key scan";
    }
  }
  const int edges = static_cast<int>(state.graph.edges().size());
  for (int e : state.heading_edges) {
    if (e < 0 || e >= edges) return "a heading edge names a missing graph edge";
  }
  if (state.has_hypothesis && (!is_key(state.hypothesis_from) || !is_key(state.hypothesis_to))) {
    return "the pending loop names a missing key scan";
  }
  if (static_cast<long>(state.scans.size()) > state.scan_count) {
    return "more scan entries than scans";
  }
  for (const LoopCloserState::ScanEntry& entry : state.scans) {
    if (entry.key < -1 || entry.key >= keys) return "a scan hangs off a missing key scan";
  }
  int last_scan = -1;
  for (const LoopCloserState::Key& k : state.keys) {
    if (k.scan_index <= last_scan || k.scan_index >= state.scan_count) {
      return "the key scans' scan numbers are not increasing below the scan count";
    }
    last_scan = k.scan_index;
  }
  keys_.clear();
  keys_.reserve(keys);
  for (const LoopCloserState::Key& k : state.keys) {
    KeyScan key;
    key.front_end = k.front_end;
    key.points = std::make_shared<const std::vector<Vector2>>(k.points);
    // As addKeyScan thins them (a released key scan has none).
    key.sparse = thinned(k.points, options_.search_point_spacing);
    key.travel_from_previous = k.travel_from_previous;
    key.retry_after = k.retry_after;
    key.scan_index = k.scan_index;
    key.stamp = k.stamp;
    key.wall_direction = k.wall_direction;
    keys_.push_back(std::move(key));
  }
  graph_ = state.graph;
  final_problem_ = PoseGraph();
  adjacency_ = state.adjacency;
  distances_from_ = -1;
  heading_edges_ = std::unordered_set<int>(state.heading_edges.begin(), state.heading_edges.end());
  counters_ = state.counters;
  scans_ = state.scans;
  first_scan_ = state.scan_count - static_cast<int>(state.scans.size());
  next_attempt_ = state.next_attempt;
  heading_loops_since_optimisation_ = state.heading_loops_since_optimisation;
  hypothesis_.reset();
  if (state.has_hypothesis) {
    hypothesis_ = Hypothesis{state.hypothesis_from, state.hypothesis_to, state.hypothesis_relative};
  }
  return "";
}

Pose2 LoopCloser::latestPose() const {
  if (scans_.empty()) return Pose2();
  const ScanEntry& s = scans_.back();
  return s.key >= 0 ? compose(graph_.pose(s.key), s.offset) : s.offset;
}

std::vector<StampedPose> LoopCloser::scanPoses() const {
  std::vector<StampedPose> out;
  out.reserve(scans_.size());
  for (const ScanEntry& s : scans_) {
    // Before the first key scan there is nothing to hang off: the front end's pose.
    out.push_back({s.stamp, s.key >= 0 ? compose(graph_.pose(s.key), s.offset) : s.offset});
  }
  return out;
}

}  // namespace ekf_slam
