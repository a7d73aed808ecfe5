#include "ekf_slam_core/pipeline/global_localization.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ekf_slam {

std::string GlobalLocalizationOptions::validate() const { return checkFields(*this); }

GlobalLocalizer::GlobalLocalizer(const SlamState& state, const ScanMatcherOptions& icp,
                                 const GlobalLocalizationOptions& options)
    : icp_(icp), options_(options) {
  const LoopCloserState& closer = state.back_end.closer;
  if (closer.keys.empty()) {
    map_error_ = "the saved state holds no key scans (it was made with loop closure off)";
    return;
  }
  if (!state.back_end.has_map_from_graph) {
    map_error_ = "the saved graph is not tied to the map frame yet";
    return;
  }
  map_from_graph_ = state.back_end.map_from_graph;
  for (size_t k = 0; k < closer.keys.size(); ++k) {
    const Pose2& pose = closer.graph.pose(static_cast<int>(k));
    for (const Vector2& p : closer.keys[k].points) map_points_.push_back(transformFrom(pose, p));
    key_graph_.push_back(pose);
    key_front_end_.push_back(closer.keys[k].front_end);
  }
  if (state.has_front_end && !state.front_end.map_points.empty()) {
    front_end_map_.emplace(state.front_end.map_points, icp_.normal_radius,
                           icp_.initial_correspondence_distance);
  }
  map_points_ = gridThinned(map_points_, icp_.min_point_spacing);
  if (static_cast<int>(map_points_.size()) < icp_.min_correspondences) {
    map_error_ = "the saved key scans hold too few readings to search";
    return;
  }
  grid_.build(map_points_, options_.correlative);
  if (grid_.empty()) {
    map_error_ = "the saved map is too large for one search grid";
    return;
  }
  map_reference_.emplace(map_points_, icp_.normal_radius, icp_.initial_correspondence_distance);
  const Vector2 low = grid_.lowerCorner(), high = grid_.upperCorner();
  centre_ = Pose2(0.5 * (low.x() + high.x()), 0.5 * (low.y() + high.y()), 0.0);
  radius_ = 0.5 * (high - low).norm();
}

GlobalPlacement GlobalLocalizer::add(const std::vector<Vector2>& robot_points,
                                     const Pose2& odometry) {
  joined_.push_back({robot_points, odometry});
  // Keep the newest scans within joined_travel of the newest (and the
  // newest alone when it moved more).
  while (static_cast<int>(joined_.size()) > options_.max_joined_scans) joined_.pop_front();
  double travel = 0.0;
  size_t first = joined_.size() - 1;
  while (first > 0) {
    const Pose2 step = between(joined_[first - 1].odometry, joined_[first].odometry);
    travel += std::hypot(step.x, step.y);
    if (travel > options_.joined_travel) break;
    --first;
  }
  joined_.erase(joined_.begin(), joined_.begin() + first);
  GlobalPlacement placement;
  placement.joined_scans = static_cast<int>(joined_.size());
  if (last_search_) {
    const Pose2 since = between(*last_search_, odometry);
    if (std::hypot(since.x, since.y) < options_.retry_travel &&
        std::abs(since.theta) < options_.retry_turn) {
      placement.message = "waiting to move on before the next search";
      return placement;
    }
  }
  last_search_ = odometry;
  std::vector<Vector2> query;
  for (const Joined& j : joined_) {
    const Pose2 offset = between(odometry, j.odometry);
    for (const Vector2& p : j.points) query.push_back(transformFrom(offset, p));
  }
  placement = search(gridThinned(query, icp_.min_point_spacing));
  placement.joined_scans = static_cast<int>(joined_.size());
  return placement;
}

void GlobalLocalizer::restart() {
  joined_.clear();
  last_search_.reset();
}

double GlobalLocalizer::fitNear(const std::vector<Vector2>& robot_points,
                                const Pose2& map_pose) const {
  if (!map_error_.empty()) return 0.0;
  const std::vector<Vector2> sparse = gridThinned(robot_points, options_.search_point_spacing);
  if (sparse.empty()) return 0.0;
  const Pose2 graph_pose = compose(inverse(map_from_graph_), map_pose);
  return correlativeSearch(sparse, grid_, graph_pose, options_.fit_window, options_.fit_angle,
                           options_.correlative)
      .score;
}

GlobalPlacement GlobalLocalizer::search(const std::vector<Vector2>& query) const {
  GlobalPlacement out;
  out.searched = true;
  std::ostringstream why;
  why.precision(3);
  if (!map_error_.empty()) {
    out.message = map_error_;
    return out;
  }
  if (static_cast<int>(query.size()) < icp_.min_correspondences) {
    why << "too few readings yet (" << query.size() << ")";
    out.message = why.str();
    return out;
  }
  const std::vector<Vector2> sparse = gridThinned(query, options_.search_point_spacing);
  const CorrelativeResult best = correlativeSearch(sparse, grid_, centre_, radius_, kPi,
                                                   options_.correlative, options_.min_score);
  out.score = best.score;
  if (best.score < options_.min_score) {
    why << "no place scores " << options_.min_score << " (best " << best.score << ")";
    out.message = why.str();
    return out;
  }
  const MatchResult fine = matchPoints(query, *map_reference_, best.pose, icp_);
  const Pose2 shift = between(best.pose, fine.pose);
  if (!fine.ok || fine.inlier_fraction < options_.min_inlier_fraction ||
      fine.rms_residual > options_.max_rms_residual ||
      std::hypot(shift.x, shift.y) > options_.max_icp_shift) {
    why << "the best place (score " << best.score << ") does not fit: ICP "
        << (fine.ok ? "" : "refused, ") << "inliers " << fine.inlier_fraction << ", rms "
        << fine.rms_residual << " m, moved " << std::hypot(shift.x, shift.y) << " m";
    out.message = why.str();
    return out;
  }
  const CorrelativeResult rival =
      correlativeRunnerUp(sparse, grid_, centre_, radius_, kPi, options_.correlative, best.pose,
                          options_.distinct_radius, options_.max_runner_up_ratio * best.score);
  out.runner_up = rival.score;
  if (rival.score > 0.0) {
    why << "ambiguous: a place " << (rival.pose.translation() - best.pose.translation()).norm()
        << " m away scores " << rival.score << " against " << best.score;
    out.message = why.str();
    return out;
  }
  out.found = true;
  out.graph_pose = fine.pose;
  out.map_pose = compose(map_from_graph_, fine.pose);
  if (front_end_map_) {
    // From the nearest key scan, whose front-end pose the front end's map
    // was drawn with there.
    size_t near = 0;
    for (size_t k = 1; k < key_graph_.size(); ++k) {
      if ((key_graph_[k].translation() - fine.pose.translation()).squaredNorm() <
          (key_graph_[near].translation() - fine.pose.translation()).squaredNorm()) {
        near = k;
      }
    }
    const Pose2 guess = compose(key_front_end_[near], between(key_graph_[near], fine.pose));
    const MatchResult local = matchPoints(query, *front_end_map_, guess, icp_);
    const Pose2 moved = between(guess, local.pose);
    if (local.ok && local.inlier_fraction >= options_.min_inlier_fraction &&
        std::hypot(moved.x, moved.y) <= options_.max_icp_shift) {
      out.has_front_end_pose = true;
      out.front_end_pose = local.pose;
    }
  }
  return out;
}

void placeRobot(const GlobalPlacement& place, const Matrix3& covariance, SlamState* state) {
  FilterState& filter = state->filter;
  filter.x(0) = place.map_pose.x;
  filter.x(1) = place.map_pose.y;
  filter.x(2) = place.map_pose.theta;
  const int landmarks = filter.dim - FilterState::kPoseDim;
  filter.P.topLeftCorner<3, 3>() = covariance;
  if (landmarks > 0) {
    filter.P.block(FilterState::kPoseDim, 0, landmarks, FilterState::kPoseDim).setZero();
    filter.P.block(0, FilterState::kPoseDim, FilterState::kPoseDim, landmarks).setZero();
  }
  // The back end hangs a new scan off the last key scan by the front end's
  // motion since it: the place found, expressed that way, puts the first
  // new scan at graph_pose, whatever frame the front end goes on in.
  const LoopCloserState& closer = state->back_end.closer;
  if (!closer.keys.empty()) {
    const int last = static_cast<int>(closer.keys.size()) - 1;
    state->back_end.last_front_end =
        compose(closer.keys[last].front_end, between(closer.graph.pose(last), place.graph_pose));
  }
  // The front end goes on on its own map where it fits there, else afresh.
  if (place.has_front_end_pose) {
    state->front_end.last_corrected = place.front_end_pose;
  } else {
    state->has_front_end = false;
  }
  state->has_last_iteration = false;
}

Matrix3 placementCovariance() {
  const double sd = 0.05, sa = degToRad(1.0);
  return Vector3(sd * sd, sd * sd, sa * sa).asDiagonal();
}

GlobalPlacement movedOn(const GlobalPlacement& place, const Pose2& motion) {
  GlobalPlacement moved = place;
  moved.graph_pose = compose(place.graph_pose, motion);
  moved.map_pose = compose(place.map_pose, motion);
  moved.front_end_pose = compose(place.front_end_pose, motion);
  return moved;
}

}  // namespace ekf_slam
