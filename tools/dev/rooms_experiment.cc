// ekf_slam_rooms_experiment: the thesis's rooms simulation (§4.4.5,
// Figs. 4.7–4.8) with this filter. Three rooms in a row joined by doors; the
// robot explores each room in turn and drives back through all of them to
// its start; the filter associates its point observations itself
// (AssociationOptions' defaults) in six modes:
//   open              nearest neighbour among every landmark of the map;
//   open_jcbb         joint compatibility (JCBB) among every landmark;
//   open_mecp         MECP association (mecp/mecp_association.h) over
//                     open: each scan's polygon round the robot matched to
//                     the remembered ones, its corners paired as a group;
//   robot_room        nearest neighbour among the landmarks of the robot's
//                     room (both rooms of a doorway within 0.8 m; no gate
//                     when its estimate is on a wall's barrier elsewhere);
//   observation_room  nearest neighbour among the landmarks of the
//                     observation's room (associateInRooms,
//                     mecp/room_gating.h);
//   observation_room_mecp  MECP association over observation_room, the
//                     thesis's own combination (§4.4.5).
// Both gates label each landmark at augmentation with
// RoomGate::roomsOf(its estimated position, the laser's estimated
// position), door jambs with both rooms; observation_room labels each
// observation the same way.
// The rooms come from the true walls (findDoorways + RoomMap, walls
// inflated by 0.25 m): the filter here maps points only, so it holds no
// walls to derive them from.
//
// The world (map frame, m):
//   walls      outer walls on x = 0, x = 18, y = 0, y = 6 (their inner
//              faces); interior walls 0.1 m thick centred on x = 6 and
//              x = 12, each with a 1 m door for y in [2.5, 3.5];
//   points     31: each room's four corners (on the faces of the interior
//              walls, 0.1 m from the next room's corners across the wall),
//              the 8 door jambs (each wall end's two corners), a post in
//              each room, and 8 pieces of furniture against the interior
//              walls, in pairs facing each other across a wall 0.5–0.6 m
//              apart;
//   path       each room's square loop 1.5 m inside its walls, from room
//              to room through the doors along y = 3, then straight back
//              to room 1: about 57 m, one lap.
// Sensing: 360° (the thesis's two lasers), 5 m range; the walls (as their
// centre lines) occlude. Noise: odometry drawn from the filter's motion
// model with MotionNoiseOptions' defaults, standard deviations times
// --odometry-noise-scale; points σ_r 0.02 m, σ_φ 0.01 rad. The filter is
// told the true noise.
//
//   ekf_slam_rooms_experiment --out DIR [--runs N] [--seed S]
//                             [--odometry-noise-scale F]
//
// Runs use seeds S, S+1, … (default 1; 20 runs); every mode sees the same
// draws for a seed. A match pairs an observation of true feature A with a
// landmark created from feature B; it is a mis-association when A ≠ B and
// a cross-wall one when A and B share no room (a jamb is in both of its
// rooms). The loop closes in a run when, back in room 1 after room 3, at
// least 90 % of the observations of features already mapped are paired
// with the landmark first made of their feature.
//
// Writes into DIR:
//   world.txt      "wall x1 y1 x2 y2", "point x y room_a room_b" (room_b −1
//                  unless a jamb), "door x1 y1 x2 y2" (the openings found)
//   mecp.txt       per MECP mode, sums over the runs: scans with a polygon
//                  round the robot, group matches and refusals, pairings
//                  the group changed, polygons remembered, and of the
//                  pairings changed those now right and those now wrong
//   summary.txt    one line per mode; columns named in its header (the
//                  cross-wall matches made with the robot's estimate within
//                  0.8 m of a doorway's centre are also counted apart)
//   runs.txt       per mode and seed: matches mis_associations cross_wall
//                  landmarks duplicates mean_pos_err_m final_pos_err_m
//   M.txt          per mode M, per step, means over the runs: step time_s
//                  pos_err_m nees cross_wall_so_far
//   M_path.txt     run 0: step x_true y_true x_est y_est
//   M_map.txt      run 0 at the end: "landmark id feature x y cxx cxy cyy"
//                  and each cross-wall match "cross step feature_seen
//                  feature_of_landmark x_robot y_robot"; the MECP modes
//                  also each remembered polygon "polygon x1 y1 x2 y2 …"
//                  (its members' estimates, counter-clockwise: the
//                  partition of thesis Fig. 4.6)
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_core/filter/data_association.h"
#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/mecp/doorways.h"
#include "ekf_slam_core/mecp/mecp_association.h"
#include "ekf_slam_core/mecp/room_gating.h"
#include "ekf_slam_core/sim/landmark_simulator.h"
#include "tools/dev/experiment_options.h"

namespace {

using ekf_slam::AssociationDecision;
using ekf_slam::EkfSlam;
using ekf_slam::FilterStatus;
using ekf_slam::kPi;
using ekf_slam::PointObservation;
using ekf_slam::Pose2;
using ekf_slam::Segment2;
using ekf_slam::Vector2;

constexpr double kRoomWidth = 6.0;  // m, along x
constexpr double kRoomDepth = 6.0;  // m, along y
constexpr int kRooms = 3;
constexpr double kHalfWall = 0.05;  // m, half an interior wall's thickness
constexpr double kDoorLow = 2.5;    // m, the doors' y extent
constexpr double kDoorHigh = 3.5;
constexpr double kMaxRange = 5.0;      // m
constexpr double kSightMargin = 1e-3;  // m: a sight line may end on the wall its point is on
// m: the room map's barrier half-width. An observed point on a wall falls
// beyond it by its position error (σ ≈ 5 cm across the ray at 5 m, more
// with the pose's heading error); past the barrier it would be labelled
// with the space behind the wall. 0.25 m is about five σ.
constexpr double kWallInflation = 0.25;

struct Feature {
  Vector2 position;
  int room_a = -1, room_b = -1;  // room_b: the other room of a door jamb
};

std::vector<Segment2> walls() {
  const double length = kRooms * kRoomWidth;
  std::vector<Segment2> w = {{{0, 0}, {length, 0}},
                             {{length, 0}, {length, kRoomDepth}},
                             {{length, kRoomDepth}, {0, kRoomDepth}},
                             {{0, kRoomDepth}, {0, 0}}};
  for (int r = 1; r < kRooms; ++r) {
    const double x = r * kRoomWidth;
    w.push_back({{x, 0}, {x, kDoorLow}});
    w.push_back({{x, kRoomDepth}, {x, kDoorHigh}});
  }
  return w;
}

std::vector<Feature> features() {
  std::vector<Feature> f;
  for (int r = 0; r < kRooms; ++r) {
    const double left = r * kRoomWidth + (r > 0 ? kHalfWall : 0.0);
    const double right = (r + 1) * kRoomWidth - (r + 1 < kRooms ? kHalfWall : 0.0);
    for (const Vector2& corner : {Vector2(left, 0), Vector2(right, 0), Vector2(right, kRoomDepth),
                                  Vector2(left, kRoomDepth)}) {
      f.push_back({corner, r, -1});
    }
    f.push_back({{r * kRoomWidth + 3.0, 3.8}, r, -1});  // a post
  }
  for (int r = 1; r < kRooms; ++r) {
    const double x = r * kRoomWidth;
    for (double y : {kDoorLow, kDoorHigh}) {
      f.push_back({{x - kHalfWall, y}, r - 1, r});
      f.push_back({{x + kHalfWall, y}, r, r - 1});
    }
    // Furniture against the wall, facing across it.
    f.push_back({{x - 0.25, 1.2}, r - 1, -1});
    f.push_back({{x + 0.25, 1.4}, r, -1});
    f.push_back({{x - 0.25, 4.8}, r - 1, -1});
    f.push_back({{x + 0.3, 4.6}, r, -1});
  }
  return f;
}

// Each room's loop starts and ends at (x + 1.5, 3); the legs between rooms
// run along y = 3 through the doors, and the last one back to room 1.
std::vector<Vector2> waypoints() {
  std::vector<Vector2> w;
  for (int r = 0; r < kRooms; ++r) {
    const double x = r * kRoomWidth;
    if (r > 0) w.emplace_back(x + 1.5, 3.0);
    for (const Vector2& p : {Vector2(x + 1.5, 1.5), Vector2(x + 4.5, 1.5), Vector2(x + 4.5, 4.5),
                             Vector2(x + 1.5, 4.5), Vector2(x + 1.5, 3.0)}) {
      w.push_back(p);
    }
  }
  w.emplace_back(1.5, 3.0);
  return w;  // the simulator closes the loop from here to the first waypoint
}

bool shareRoom(const Feature& a, const Feature& b) {
  for (int ra : {a.room_a, a.room_b}) {
    if (ra >= 0 && (ra == b.room_a || ra == b.room_b)) return true;
  }
  return false;
}

double cross(const Vector2& a, const Vector2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Whether the open segments p–q and a–b cross.
bool segmentsCross(const Vector2& p, const Vector2& q, const Vector2& a, const Vector2& b) {
  const double d1 = cross(q - p, a - p), d2 = cross(q - p, b - p);
  const double d3 = cross(b - a, p - a), d4 = cross(b - a, q - a);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 &&
         d4 != 0;
}

bool inSight(const Vector2& sensor, const Vector2& point, const std::vector<Segment2>& walls) {
  const Vector2 to = point - sensor;
  const double length = to.norm();
  if (length <= kSightMargin) return true;
  const Vector2 end = sensor + to * ((length - kSightMargin) / length);
  for (const Segment2& w : walls) {
    if (segmentsCross(sensor, end, w.start, w.end)) return false;
  }
  return true;
}

enum class Mode { kOpen, kOpenJcbb, kOpenMecp, kRobotRoom, kObservationRoom, kObservationRoomMecp };
constexpr Mode kModes[] = {Mode::kOpen,      Mode::kOpenJcbb,        Mode::kOpenMecp,
                           Mode::kRobotRoom, Mode::kObservationRoom, Mode::kObservationRoomMecp};
const char* modeName(Mode m) {
  switch (m) {
    case Mode::kOpen:
      return "open";
    case Mode::kOpenJcbb:
      return "open_jcbb";
    case Mode::kOpenMecp:
      return "open_mecp";
    case Mode::kRobotRoom:
      return "robot_room";
    case Mode::kObservationRoom:
      return "observation_room";
    case Mode::kObservationRoomMecp:
      return "observation_room_mecp";
  }
  return "unknown";
}

// Association among the landmarks of the rooms the sensor's estimate is in.
ekf_slam::AssociationResult associateInRobotRoom(const EkfSlam& filter,
                                                 const std::vector<PointObservation>& observations,
                                                 const ekf_slam::AssociationOptions& options,
                                                 const ekf_slam::RoomGate& gate) {
  const Vector2 sensor =
      ekf_slam::compose(filter.pose(), filter.options().laser_pose).translation();
  const std::vector<int> here = gate.roomsOf(sensor, sensor);
  std::vector<int> elsewhere;
  for (const ekf_slam::LandmarkInfo& info : filter.landmarks()) {
    if (!gate.allows(info.id, here)) elsewhere.push_back(info.id);
  }
  EkfSlam in_room = filter;
  in_room.removeLandmarks(elsewhere);
  return ekf_slam::associate(in_room, observations, options);
}

struct StepStats {
  double pos = 0, nees = 0, cross_wall = 0;
};

struct RunResult {
  long matches = 0, mis = 0, cross_wall = 0;
  // Of those, with the robot's estimate in a doorway (within the gate's
  // doorway_radius of its centre).
  long cross_wall_at_door = 0;
  int landmarks = 0, duplicates = 0;
  double mean_pos = 0, final_pos = 0;
  long refused = 0;
  // Back in room 1 after room 3: observations of features already mapped,
  // and of those the ones paired with the landmark first made of their
  // feature (the loop closed on them).
  long return_observations = 0, return_right = 0;
  ekf_slam::MecpCounters mecp;  // the MECP modes'
  // The MECP modes: pairings the group changed from its base association's
  // that are right (the feature's own landmark) and wrong.
  long group_fixed = 0, group_broke = 0;
  bool loopClosed() const {
    return return_observations > 0 && return_right >= 0.9 * return_observations;
  }
};

void runOnce(Mode mode, unsigned seed, double noise_scale, const ekf_slam::RoomGate& gate_template,
             std::vector<StepStats>* stats, RunResult* run, std::ofstream* path_out,
             std::ofstream* map_out) {
  const std::vector<Feature> truth = features();
  const std::vector<Segment2> wall_list = walls();
  ekf_slam::sim::LandmarkSimOptions sim_options;
  sim_options.seed = seed;
  for (const Feature& f : truth) sim_options.landmarks.push_back(f.position);
  sim_options.waypoints = waypoints();
  sim_options.max_range = kMaxRange;
  sim_options.field_of_view = 2.0 * kPi;
  ekf_slam::scaleOdometryNoise(noise_scale, &sim_options.odometry_noise);
  ekf_slam::sim::LandmarkSimulator sim(sim_options);

  ekf_slam::FilterOptions options;
  options.laser_pose = sim_options.laser_pose;
  options.motion_noise = sim_options.odometry_noise;
  options.tentative_max_age = 0;  // every observation is of a real feature
  EkfSlam filter(options, sim.current().true_pose);
  ekf_slam::RoomGate gate = gate_template;
  ekf_slam::AssociationOptions association;
  if (mode == Mode::kOpenJcbb)
    association.method = ekf_slam::AssociationMethod::kJointCompatibility;
  ekf_slam::MecpAssociation mecp;
  std::unordered_map<int, int> feature_of;      // landmark id → the feature it was created from
  std::unordered_map<int, int> first_landmark;  // feature → the landmark first made of it
  bool been_in_last_room = false;

  auto step = [&](size_t k, const ekf_slam::sim::SimStep& s) {
    const Vector2 sensor = ekf_slam::compose(s.true_pose, sim_options.laser_pose).translation();
    std::vector<PointObservation> observations;
    std::vector<int> seen;
    for (size_t i = 0; i < s.observations.size(); ++i) {
      if (!inSight(sensor, truth[s.true_landmark[i]].position, wall_list)) continue;
      observations.push_back(s.observations[i]);
      seen.push_back(s.true_landmark[i]);
    }
    const Vector2 robot = filter.pose().translation();
    ekf_slam::AssociationResult result, base;
    const ekf_slam::Associator in_rooms = [&](const EkfSlam& f,
                                              const std::vector<PointObservation>& o,
                                              const ekf_slam::AssociationOptions& a) {
      return ekf_slam::associateInRooms(f, o, a, gate);
    };
    switch (mode) {
      case Mode::kOpen:
      case Mode::kOpenJcbb:
        result = ekf_slam::associate(filter, observations, association);
        break;
      case Mode::kOpenMecp:
        result = mecp.associate(filter, observations, association, nullptr);
        base = ekf_slam::associate(filter, observations, association);
        break;
      case Mode::kRobotRoom:
        result = associateInRobotRoom(filter, observations, association, gate);
        break;
      case Mode::kObservationRoom:
        result = in_rooms(filter, observations, association);
        break;
      case Mode::kObservationRoomMecp:
        result = mecp.associate(filter, observations, association, in_rooms);
        base = in_rooms(filter, observations, association);
        break;
    }
    for (size_t i = 0; i < base.observations.size(); ++i) {
      const int before = base.observations[i].decision == AssociationDecision::kMatched
                             ? base.observations[i].landmark_id
                             : -1;
      const int after = result.observations[i].decision == AssociationDecision::kMatched
                            ? result.observations[i].landmark_id
                            : -1;
      if (after == before || after < 0) continue;
      if (feature_of.at(after) == seen[i]) {
        ++run->group_fixed;
      } else {
        ++run->group_broke;
      }
    }
    const std::vector<ekf_slam::PointMatch> matches = result.matches();
    if (s.true_pose.x > (kRooms - 1) * kRoomWidth) been_in_last_room = true;
    if (been_in_last_room && s.true_pose.x < kRoomWidth) {
      std::vector<int> paired(observations.size(), -1);
      for (const ekf_slam::PointMatch& m : matches) paired[m.observation] = m.landmark_id;
      for (size_t i = 0; i < observations.size(); ++i) {
        const auto first = first_landmark.find(seen[i]);
        if (first == first_landmark.end()) continue;
        ++run->return_observations;
        if (paired[i] == first->second) ++run->return_right;
      }
    }
    for (const ekf_slam::PointMatch& m : matches) {
      const int a = seen[m.observation], b = feature_of.at(m.landmark_id);
      ++run->matches;
      if (a == b) continue;
      ++run->mis;
      if (shareRoom(truth[a], truth[b])) continue;
      ++run->cross_wall;
      for (const ekf_slam::Doorway& door : gate.doorways()) {
        if ((robot - door.centre()).norm() <= ekf_slam::RoomGateOptions().doorway_radius) {
          ++run->cross_wall_at_door;
          break;
        }
      }
      if (map_out) {
        *map_out << "cross " << k << ' ' << a << ' ' << b << ' ' << robot.x() << ' ' << robot.y()
                 << '\n';
      }
    }
    if (filter.update(observations, matches) != FilterStatus::kOk) ++run->refused;
    ekf_slam::IterationReport report;
    report.matches = matches;
    for (int i : result.newLandmarks()) {
      int id = -1;
      if (filter.augment(observations[i], &id) != FilterStatus::kOk) {
        ++run->refused;
        continue;
      }
      report.created.push_back({i, id});
      feature_of[id] = seen[i];
      first_landmark.emplace(seen[i], id);
      gate.labelLandmark(id, filter.landmarkPosition(filter.slotOf(id)),
                         ekf_slam::compose(filter.pose(), options.laser_pose).translation());
    }
    mecp.remember(filter, report);

    if (stats->size() <= k) stats->resize(k + 1);
    StepStats& st = (*stats)[k];
    const Pose2 est = filter.pose();
    const double pos_err = std::hypot(est.x - s.true_pose.x, est.y - s.true_pose.y);
    st.pos += pos_err;
    if (k > 0) st.nees += filter.poseNees(s.true_pose);
    st.cross_wall += run->cross_wall;
    run->mean_pos += pos_err;
    run->final_pos = pos_err;
    if (path_out) {
      *path_out << k << ' ' << s.true_pose.x << ' ' << s.true_pose.y << ' ' << est.x << ' ' << est.y
                << '\n';
    }
  };

  step(0, sim.current());
  Pose2 odom = sim.current().odometry;
  size_t k = 0;
  while (sim.next()) {
    const ekf_slam::sim::SimStep& s = sim.current();
    if (filter.predict(odom, s.odometry, sim_options.dt) != FilterStatus::kOk) ++run->refused;
    odom = s.odometry;
    step(++k, s);
  }
  run->mean_pos /= k + 1;
  run->landmarks = filter.landmarkCount();
  run->mecp = mecp.counters();
  std::vector<int> mapped;
  for (const auto& entry : feature_of) mapped.push_back(entry.second);
  std::sort(mapped.begin(), mapped.end());
  run->duplicates = static_cast<int>(mapped.size() -
                                     (std::unique(mapped.begin(), mapped.end()) - mapped.begin()));
  if (map_out) {
    for (const ekf_slam::LandmarkInfo& info : filter.landmarks()) {
      const int slot = filter.slotOf(info.id);
      const Vector2 m = filter.landmarkPosition(slot);
      const ekf_slam::Matrix2 c = filter.landmarkCovariance(slot);
      *map_out << "landmark " << info.id << ' ' << feature_of.at(info.id) << ' ' << m.x() << ' '
               << m.y() << ' ' << c(0, 0) << ' ' << c(0, 1) << ' ' << c(1, 1) << '\n';
    }
    for (const std::vector<int>& polygon : mecp.polygons()) {  // the MECP modes' partition
      std::string line = "polygon";
      bool complete = true;
      for (int id : polygon) {
        const int slot = filter.slotOf(id);
        if (slot < 0) {
          complete = false;
          break;
        }
        const Vector2 m = filter.landmarkPosition(slot);
        line += ' ' + std::to_string(m.x()) + ' ' + std::to_string(m.y());
      }
      if (complete) *map_out << line << '\n';
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  ekf_slam::ExperimentOptions options;
  options.runs = 20;
  if (!ekf_slam::parseExperimentOptions(argc, argv, "ekf_slam_rooms_experiment", &options))
    return 2;
  const std::string& out_dir = options.out_dir;
  const int runs = options.runs;
  const unsigned first_seed = options.first_seed;
  const double noise_scale = options.noise_scale;
  const std::string dir = out_dir + "/";

  const std::vector<Segment2> wall_list = walls();
  const std::vector<ekf_slam::Doorway> doorways = ekf_slam::findDoorways(
      wall_list, ekf_slam::DoorwayOptions(), ekf_slam::crossesNoWall(wall_list));
  ekf_slam::RoomMap rooms;
  ekf_slam::RoomMapOptions room_options;
  room_options.wall_inflation = kWallInflation;
  const std::string error = rooms.build(wall_list, doorways, room_options);
  if (!error.empty() || static_cast<int>(doorways.size()) != kRooms - 1) {
    std::cerr << "ekf_slam_rooms_experiment: the rooms were not found (" << doorways.size()
              << " doorways) " << error << "\n";
    return 1;
  }
  const ekf_slam::RoomGate gate(rooms, doorways);
  {
    std::ofstream world(dir + "world.txt");
    if (!world) {
      std::cerr << "ekf_slam_rooms_experiment: cannot write into " << out_dir << "\n";
      return 2;
    }
    world << "# wall x1 y1 x2 y2 | point x y room_a room_b | door x1 y1 x2 y2 (map frame, m)\n";
    for (const Segment2& w : wall_list) {
      world << "wall " << w.start.x() << ' ' << w.start.y() << ' ' << w.end.x() << ' ' << w.end.y()
            << '\n';
    }
    for (const Feature& f : features()) {
      world << "point " << f.position.x() << ' ' << f.position.y() << ' ' << f.room_a << ' '
            << f.room_b << '\n';
    }
    for (const ekf_slam::Doorway& d : doorways) {
      world << "door " << d.end_a.x() << ' ' << d.end_a.y() << ' ' << d.end_b.x() << ' '
            << d.end_b.y() << '\n';
    }
  }

  const ekf_slam::ChiSquareBand band = ekf_slam::averageChiSquareBand(3, runs, 0.95);
  std::ofstream summary(dir + "summary.txt");
  summary << "# mode runs steps mean_pos_err_m final_pos_err_m average_nees band_lower band_upper "
             "matches_per_run mis_per_run cross_wall_per_run cross_wall_total "
             "cross_wall_at_door_total runs_with_cross_wall landmarks_per_run "
             "duplicates_per_run refused loops_closed return_right_fraction\n";
  std::ofstream mecp_out(dir + "mecp.txt");
  mecp_out << "# mode scans_with_polygon group_matches group_refused pairings_changed "
              "polygons_remembered changed_right changed_wrong (sums over the runs)\n";
  std::ofstream per_run(dir + "runs.txt");
  per_run << "# mode seed matches mis_associations cross_wall landmarks duplicates "
             "mean_pos_err_m final_pos_err_m\n";
  const double dt = ekf_slam::sim::LandmarkSimOptions().dt;
  for (Mode mode : kModes) {
    const std::string name = modeName(mode);
    std::vector<StepStats> stats;
    std::ofstream path(dir + name + "_path.txt");
    path << "# step x_true y_true x_est y_est (run 0)\n";
    std::ofstream map_out(dir + name + "_map.txt");
    map_out << "# landmark id feature x y cxx cxy cyy | cross step feature_seen "
               "feature_of_landmark x_robot y_robot | polygon x1 y1 x2 y2 ... (run 0)\n";
    RunResult total;
    int runs_with_cross = 0, loops_closed = 0;
    double final_pos = 0;
    for (int r = 0; r < runs; ++r) {
      RunResult run;
      runOnce(mode, first_seed + r, noise_scale, gate, &stats, &run, r == 0 ? &path : nullptr,
              r == 0 ? &map_out : nullptr);
      per_run << name << ' ' << first_seed + r << ' ' << run.matches << ' ' << run.mis << ' '
              << run.cross_wall << ' ' << run.landmarks << ' ' << run.duplicates << ' '
              << run.mean_pos << ' ' << run.final_pos << '\n';
      total.matches += run.matches;
      total.mis += run.mis;
      total.cross_wall += run.cross_wall;
      total.cross_wall_at_door += run.cross_wall_at_door;
      total.landmarks += run.landmarks;
      total.duplicates += run.duplicates;
      total.refused += run.refused;
      final_pos += run.final_pos;
      if (run.cross_wall > 0) ++runs_with_cross;
      if (run.loopClosed()) ++loops_closed;
      total.return_observations += run.return_observations;
      total.mecp.mecp_polygons += run.mecp.mecp_polygons;
      total.mecp.mecp_group_matches += run.mecp.mecp_group_matches;
      total.mecp.mecp_group_refused += run.mecp.mecp_group_refused;
      total.mecp.mecp_pairings_changed += run.mecp.mecp_pairings_changed;
      total.mecp.mecp_remembered += run.mecp.mecp_remembered;
      total.group_fixed += run.group_fixed;
      total.group_broke += run.group_broke;
      total.return_right += run.return_right;
    }
    std::ofstream out(dir + name + ".txt");
    out << "# " << name << ", " << runs
        << " runs; means over runs. step time_s pos_err_m nees cross_wall_so_far\n";
    double pos_total = 0, nees_total = 0;
    for (size_t k = 0; k < stats.size(); ++k) {
      const StepStats& st = stats[k];
      const double nees = k > 0 ? st.nees / runs : std::nan("");
      out << k << ' ' << k * dt << ' ' << st.pos / runs << ' ' << nees << ' '
          << st.cross_wall / runs << '\n';
      pos_total += st.pos / runs;
      if (k > 0) nees_total += nees;
    }
    const size_t steps = stats.size();
    char line[512];
    std::snprintf(line, sizeof line,
                  "%s %d %zu %.4f %.4f %.3f %.3f %.3f %.1f %.2f %.2f %ld %ld %d %.2f %.2f %ld %d "
                  "%.3f\n",
                  name.c_str(), runs, steps, pos_total / steps, final_pos / runs,
                  nees_total / (steps - 1), band.lower, band.upper,
                  static_cast<double>(total.matches) / runs, static_cast<double>(total.mis) / runs,
                  static_cast<double>(total.cross_wall) / runs, total.cross_wall,
                  total.cross_wall_at_door, runs_with_cross,
                  static_cast<double>(total.landmarks) / runs,
                  static_cast<double>(total.duplicates) / runs, total.refused, loops_closed,
                  total.return_observations > 0
                      ? static_cast<double>(total.return_right) / total.return_observations
                      : std::nan(""));
    summary << line;
    std::cout << line;
    if (mode == Mode::kOpenMecp || mode == Mode::kObservationRoomMecp) {
      mecp_out << name << ' ' << total.mecp.mecp_polygons << ' ' << total.mecp.mecp_group_matches
               << ' ' << total.mecp.mecp_group_refused << ' ' << total.mecp.mecp_pairings_changed
               << ' ' << total.mecp.mecp_remembered << ' ' << total.group_fixed << ' '
               << total.group_broke << '\n';
    }
  }
  return 0;
}
