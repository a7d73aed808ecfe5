// Global localisation in a saved map: where the robot stands in the map of
// a saved SLAM state when nobody says (another day, another door; a robot
// carried while switched off), from its first scans alone.
//
// The map is the key scans' readings placed by the saved loop-closed graph,
// one likelihood grid of the whole building. The robot's latest scans,
// joined by the odometry into the newest one's frame (one 180° sweep is
// often alike at several places; a few metres of them rarely are), are
// searched over the whole grid at every heading by the correlative
// matcher's branch and bound (correlative_matcher.h), refined by ICP
// against the map's points, and taken when
// - the search scores at least min_score,
// - ICP pairs at least min_inlier_fraction of them within max_rms_residual
//   and moves the search's pose by at most max_icp_shift,
// - and no place farther than distinct_radius scores above
//   max_runner_up_ratio of the best (a corridor of identical doors, two
//   rooms alike: then more scans are needed).
// placeRobot then moves the saved state's robot there, so that a run
// resumed from it starts at the place found.
//
// A robot localising in the saved map can lose its place (carried, a wheel
// slipping on a ramp, a start pose given wrongly): LostDetector watches how
// well each scan fits the map where the robot is estimated to stand
// (GlobalLocalizer::fitNear), and when it stops fitting, the search above
// finds the robot again.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/loop_closure/correlative_matcher.h"
#include "ekf_slam_core/pipeline/slam_state.h"
#include "ekf_slam_core/scan_matching/scan_matcher.h"

namespace ekf_slam {

// A whole building at every heading is a far larger window than a loop
// closure's (seconds a search on Intel): the search is tried again only once
// the robot has moved on. A coarser lattice (0.1 m, 1°) was faster but put
// Intel's scans at wrong places that ICP then refused.
struct GlobalLocalizationOptions {
  CorrelativeMatcherOptions correlative;  // the search's grid and steps
  double search_point_spacing = 0.1;      // m: the query thinned for the search
  double joined_travel = 3.0;             // m: the latest scans joined into the query
  int max_joined_scans = 40;              // at most this many of them
  double retry_travel = 0.5;              // m: moved this far (or turned retry_turn) for a new try
  double retry_turn = 0.5;                // rad
  double min_score = 0.6;                 // mean likelihood of the query at the place
  // Of the query's points paired by ICP: as a loop's (LoopClosureOptions),
  // a place seen again later keeps fewer of its points.
  double min_inlier_fraction = 0.6;
  double max_rms_residual = 0.05;     // m, ICP point-to-line
  double max_icp_shift = 0.3;         // m: ICP may move the search's pose this far
  double distinct_radius = 2.0;       // m: another place is this far from the best
  double max_runner_up_ratio = 0.85;  // of the best score
  // Lost (LostDetector): lost_scans scans in a row fit under lost_score
  // near where the robot is estimated to stand (fitNear: the best place
  // within fit_window and fit_angle, so that a robot localised a few
  // centimetres or a degree off, as a causal estimate is, still fits).
  // A localised scan fits about as the search's min_score asks of a found
  // place; one from metres away fits near nothing. A scan of a part the
  // saved map never saw fits badly too: it starts a search, which finds
  // nothing there and changes nothing.
  double lost_score = 0.3;
  int lost_scans = 5;
  double fit_window = 0.15;  // m
  double fit_angle = 0.05;   // rad

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.section("correlative", correlative);
    v.number("search_point_spacing", search_point_spacing, Bounds::openClosed(0.0, 5.0, "m"));
    v.number("joined_travel", joined_travel, Bounds::closed(0.0, 100.0, "m"));
    v.integer("max_joined_scans", max_joined_scans, Bounds::closed(1, 1000));
    v.number("retry_travel", retry_travel, Bounds::closed(0.0, 100.0, "m"));
    v.number("retry_turn", retry_turn, Bounds::closed(0.0, 10.0, "rad"));
    v.number("min_score", min_score, Bounds::openClosed(0.0, 1.0));
    v.number("min_inlier_fraction", min_inlier_fraction, Bounds::closed(0.0, 1.0));
    v.number("max_rms_residual", max_rms_residual, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("max_icp_shift", max_icp_shift, Bounds::openClosed(0.0, 100.0, "m"));
    v.number("distinct_radius", distinct_radius, Bounds::openClosed(0.0, 1000.0, "m"));
    v.number("max_runner_up_ratio", max_runner_up_ratio, Bounds::openClosed(0.0, 1.0));
    v.number("lost_score", lost_score, Bounds::closed(0.0, 1.0));
    v.integer("lost_scans", lost_scans, Bounds::closed(1, 100000));
    v.number("fit_window", fit_window, Bounds::closed(0.0, 100.0, "m"));
    v.number("fit_angle", fit_angle, Bounds::closed(0.0, kPi, "rad"));
  }

  std::string validate() const;  // empty when valid, else names the bad field
};

// Where the robot was found (or why not yet).
struct GlobalPlacement {
  bool searched = false;  // false: no search at this scan (waiting to move on)
  bool found = false;
  Pose2 graph_pose;  // the newest scan's robot pose in the saved graph's frame
  Pose2 map_pose;    // the same in the map frame
  // The same in the saved front end's frame, where its map was drawn (the
  // loops closed since bend that frame away from the graph's): found by
  // ICP against the front end's map from the nearest key scan's front-end
  // pose. False when the state has no front-end map or it did not fit.
  bool has_front_end_pose = false;
  Pose2 front_end_pose;
  double score = 0.0;
  double runner_up = 0.0;  // the best score farther than distinct_radius (0: none)
  int joined_scans = 0;    // scans in the query
  std::string message;     // why it was not taken
};

class GlobalLocalizer {
 public:
  // `icp`: the scan matcher's settings (normals, gates) of the run that made
  // the map. The state must outlive nothing: its map is copied.
  GlobalLocalizer(const SlamState& state, const ScanMatcherOptions& icp,
                  const GlobalLocalizationOptions& options);

  // Empty when the state holds a map to search, else why not (no key
  // scans: loop closure was off; their readings all released).
  const std::string& mapError() const { return map_error_; }

  // Adds a scan (its readings in the robot frame, the raw odometry at it)
  // and searches the map for the robot at it with the scans joined so far:
  // at the first scan, then each time the robot has moved retry_travel or
  // turned retry_turn since the last search (between them: not found,
  // "waiting to move on").
  GlobalPlacement add(const std::vector<Vector2>& robot_points, const Pose2& odometry);
  // Forgets the scans joined so far and where the last search was: the
  // next add searches at once (a robot found lost: the scans before were
  // taken where it no longer is).
  void restart();

  // How well the saved map explains a scan (its readings in the robot
  // frame) near `map_pose`: the best mean likelihood of its points, thinned
  // as for a search, within fit_window and fit_angle of it, as a search
  // scores a place (0 to 1). 0 when there is no map or no reading.
  double fitNear(const std::vector<Vector2>& robot_points, const Pose2& map_pose) const;

 private:
  GlobalPlacement search(const std::vector<Vector2>& query) const;

  ScanMatcherOptions icp_;
  GlobalLocalizationOptions options_;
  std::string map_error_;
  Pose2 map_from_graph_;
  LikelihoodGrid grid_;
  std::vector<Vector2> map_points_;
  std::optional<PointCloudReference> map_reference_;  // the map's points for ICP
  std::optional<PointCloudReference> front_end_map_;
  std::vector<Pose2> key_graph_, key_front_end_;
  Pose2 centre_;       // the grid's centre (the search's guess)
  double radius_ = 0;  // half the grid's diagonal (the search's window)
  struct Joined {
    std::vector<Vector2> points;
    Pose2 odometry;
  };
  std::deque<Joined> joined_;
  std::optional<Pose2> last_search_;  // the odometry at the last search
};

// Whether a robot localising in a saved map is lost: fed each scan's
// GlobalLocalizer::fitNear near the pose the robot is estimated at, it says
// lost once lost_scans of them in a row scored under lost_score, and stays
// so until reset (the robot found again).
class LostDetector {
 public:
  explicit LostDetector(const GlobalLocalizationOptions& options = GlobalLocalizationOptions())
      : lost_score_(options.lost_score), lost_scans_(options.lost_scans) {}
  // True when lost (from this scan on).
  bool add(double score) {
    low_in_a_row_ = score < lost_score_ ? low_in_a_row_ + 1 : 0;
    if (low_in_a_row_ >= lost_scans_) lost_ = true;
    return lost_;
  }
  bool lost() const { return lost_; }
  void reset() {
    lost_ = false;
    low_in_a_row_ = 0;
  }

 private:
  double lost_score_;
  int lost_scans_;
  int low_in_a_row_ = 0;
  bool lost_ = false;
};

// Moves the saved run's robot to the place found, with the pose covariance
// `covariance`, uncorrelated with the map: the filter's pose (map_pose),
// the front end's (front_end_pose, on its own map; without one the front
// end starts afresh) and the back end's link (the first new scan at
// graph_pose). Where the saved run stopped is forgotten: no motion is
// taken from the saved odometry. Resume the state with
// ResumeAt::kPlacedRobot.
void placeRobot(const GlobalPlacement& place, const Matrix3& covariance, SlamState* state);

// The pose covariance a place found is given: ICP against the map places
// the robot as well as a scan match does (5 cm, 1 deg, 1 sigma).
Matrix3 placementCovariance();

// The place found for a scan, carried on to a later one by the robot's
// motion between them (its odometry increment): a search that took a while
// placed a robot that has driven on since.
GlobalPlacement movedOn(const GlobalPlacement& place, const Pose2& motion);

}  // namespace ekf_slam
