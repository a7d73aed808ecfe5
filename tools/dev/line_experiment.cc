// ekf_slam_line_experiment: the line-feature simulation of the thesis
// (§4.3.5, Figs. 4.1–4.4) with this filter. A 22 m × 22 m room with sparse
// point features and walls; the robot drives a closed path of about 98 m
// once; the filter runs with known association (ground-truth ids; see
// --association below) in six variants that differ only in the features it
// uses:
//   points                 the 24 point features alone
//   ptheta_lines           points + walls as (p, θ) lines (kLine)
//   theta_lines            points + walls as θ-only lines (kLineAngle), the
//                          offset from the wall's end points when they are
//                          in the state (thesis eqs. 4.35, 4.38)
//   theta_lines_no_ends    points + θ-only lines, the end points never used
//   points_360             points alone, seen all round (two lasers, §4.4)
//   points_mecp_360        points seen all round, associated by MECP (thesis
//                          §4.4.3; mecp/mecp_association.h): each scan's
//                          maximum empty convex polygon around the robot
//                          matched against the polygons remembered and its
//                          corners paired as a group, the other points by
//                          nearest neighbour, whatever --association says
// The MECP needs points on every side of the robot, which a 180° laser
// does not give (the thesis assumes two lasers), hence its own baseline.
//
// The world (map frame centred on the room, m):
//   outer walls  the square (±11, ±11);
//   interior     y = 5.5 for x in [-5, 5]; x = 5.5 for y in [-6, 1];
//                x = 0.5 for y in [-1.5, 1.5] (inside the inner loop);
//   points       24: the 4 room corners and the 6 ends of the interior
//                walls (each wall's end points, used by theta_lines), and
//                14 free-standing posts;
//   path         (-8,-8) (8,-8) (8,8) (-8,8) (-8,-3) (3,-3) (3,3) (-3,3)
//                (-3,-8) and back to (-8,-8): about 98 m, one lap.
// Sensing: a 7 m range and a 180° field of view (360° for the _360
// variants) for points and walls alike;
// a wall is seen when the part of it inside range and field of view is at
// least 1 m long. Nothing occludes anything (the thesis's Player/Stage run
// did have occlusion: points behind walls are seen here).
// Noise: odometry as the landmark simulator draws it from the filter's
// motion model with MotionNoiseOptions' defaults (rot_per_rot 0.01,
// rot_per_trans 0.0005, trans_per_trans 0.01, trans_per_rot 0.0001, no
// floors, no per-metre terms; standard deviations scaled by
// --odometry-noise-scale) at ≤ 0.15 m and ≤ 0.15 rad per step; points
// σ_r 0.02 m, σ_φ 0.01 rad; lines σ_p 0.02 m, σ_θ 0.01 rad (the thesis does
// not state its simulation's noise). The filter is told the true noise.
//
//   ekf_slam_line_experiment --out DIR [--runs N] [--seed S]
//                            [--odometry-noise-scale F] [--association nn]
//                            [--line-noise endpoints] [--occlusion]
//                            [--steer-by-estimate]
//
// Runs use seeds S, S+1, … (default 1); F (default 1) multiplies the
// odometry noise's standard deviations, in the simulator and the filter.
// The other options bring the run nearer the thesis's own (§4.3.5), where
// its explanations can be tested:
//   --association nn        the points are associated by nearest neighbour
//                           with the ln|S| term (filter/data_association.h),
//                           not by their true identity; a pairing with
//                           another feature's landmark counts as wrong. The
//                           walls keep their identity (seven walls far
//                           apart: their association is not in question).
//   --line-noise endpoints  a wall is measured as the line through its two
//                           visible end readings (range-bearing noise as a
//                           point's), with the covariance T R Tᵀ of the
//                           thesis's eqs. 4.31-4.34, instead of a Gaussian in
//                           (p, θ) the filter is told exactly.
//   --occlusion             walls hide the points behind them.
//   --steer-by-estimate     the robot steers for its waypoints by the
//                           filter's pose, so a wrong estimate takes it off
//                           the planned path, as a real robot.
//
// Writes into DIR, per variant V:
//   V.txt         per step, means over the runs: step time_s pos_err_m
//                 heading_err_rad nees point_err_m line_angle_err_rad
//                 line_p_err_m points_in_map lines_in_map
//                 (feature errors average over the features in each run's
//                 map; nan where no run has one; line_p_err only for
//                 ptheta_lines)
//   V_path.txt    run 0: step x_true y_true x_est y_est
//   V_map.txt     run 0 at the end: "point i x_true y_true x_est y_est" and
//                 "line i theta_true p_true theta_est p_est" (θ-only lines:
//                 p from the estimated end points, nan without them)
// and runs.txt (per variant and seed: mean_pos_err_m final_pos_err_m
// mean_point_err_m wrong_associations duplicate_landmarks), mecp.txt (per MECP variant: scans
// with a polygon, group matches and refusals, pairings the group changed, polygons remembered),
// world.txt (the walls "wall x1 y1 x2 y2" and points "point x y") and summary.txt (one line per
// variant; columns named in its header; the options of the run on its first line).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_core/filter/data_association.h"
#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/mecp/mecp_association.h"
#include "ekf_slam_core/sim/landmark_simulator.h"
#include "tools/dev/experiment_options.h"

namespace {

using ekf_slam::EkfSlam;
using ekf_slam::FilterStatus;
using ekf_slam::kPi;
using ekf_slam::LandmarkKind;
using ekf_slam::LineMatch;
using ekf_slam::LineObservation;
using ekf_slam::Matrix2;
using ekf_slam::PointMatch;
using ekf_slam::PolarLine;
using ekf_slam::Pose2;
using ekf_slam::Vector2;
using ekf_slam::wrapAngle;

constexpr double kMaxRange = 7.0;          // m
constexpr double kFieldOfView = kPi;       // rad
constexpr double kMinVisibleLength = 1.0;  // m of wall inside range and view
constexpr double kLinePSigma = 0.02;       // m
constexpr double kLineThetaSigma = 0.01;   // rad
const double kNan = std::numeric_limits<double>::quiet_NaN();

// The options beyond ExperimentOptions (see the top of the file).
struct Conditions {
  bool nearest_neighbour = false;
  bool endpoint_lines = false;
  bool occlusion = false;
  bool steer_by_estimate = false;

  std::string describe() const {
    return std::string("association ") + (nearest_neighbour ? "nn" : "known") + ", line noise " +
           (endpoint_lines ? "endpoints" : "gaussian") + (occlusion ? ", occlusion" : "") +
           (steer_by_estimate ? ", steering by the estimate" : "");
  }
};

// Takes this file's options out of argv (the rest is ExperimentOptions').
// False on a bad value.
bool takeConditions(int* argc, char** argv, Conditions* c) {
  int kept = 1;
  for (int i = 1; i < *argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < *argc;
    if (arg == "--association" && has_value) {
      const std::string v = argv[++i];
      if (v != "nn" && v != "known") return false;
      c->nearest_neighbour = v == "nn";
    } else if (arg == "--line-noise" && has_value) {
      const std::string v = argv[++i];
      if (v != "endpoints" && v != "gaussian") return false;
      c->endpoint_lines = v == "endpoints";
    } else if (arg == "--occlusion") {
      c->occlusion = true;
    } else if (arg == "--steer-by-estimate") {
      c->steer_by_estimate = true;
    } else {
      argv[kept++] = argv[i];
    }
  }
  *argc = kept;
  return true;
}

struct Wall {
  int end[2];  // indices into points()
};

const std::vector<Vector2>& points() {
  static const std::vector<Vector2> p = {// room corners 0–3
                                         {-11, -11},
                                         {11, -11},
                                         {11, 11},
                                         {-11, 11},
                                         // interior wall ends 4–9
                                         {-5, 5.5},
                                         {5, 5.5},
                                         {5.5, -6},
                                         {5.5, 1},
                                         {0.5, -1.5},
                                         {0.5, 1.5},
                                         // posts 10–23
                                         {-5, -10},
                                         {2, -10},
                                         {10, -5},
                                         {10, 3},
                                         {6, 10},
                                         {-2, 10},
                                         {-10, 6},
                                         {-10, -1},
                                         {-5.5, 0},
                                         {-1, -5.5},
                                         {6.5, -9.5},
                                         {-1.5, 1.0},
                                         {1.5, -6},
                                         {-6, -5.5}};
  return p;
}

const std::vector<Wall>& walls() {
  static const std::vector<Wall> w = {{{0, 1}}, {{1, 2}}, {{2, 3}}, {{3, 0}},
                                      {{4, 5}}, {{6, 7}}, {{8, 9}}};
  return w;
}

std::vector<Vector2> waypoints() {
  return {{-8, -8}, {8, -8}, {8, 8}, {-8, 8}, {-8, -3}, {3, -3}, {3, 3}, {-3, 3}, {-3, -8}};
}

// The wall's infinite line in normal form, p >= 0.
PolarLine wallLine(const Wall& wall) {
  const Vector2 a = points()[wall.end[0]], b = points()[wall.end[1]];
  const Vector2 u = (b - a).normalized();
  Vector2 n(-u.y(), u.x());
  double p = n.dot(a);
  if (p < 0.0) {
    n = -n;
    p = -p;
  }
  return PolarLine{p, std::atan2(n.y(), n.x())};
}

// The part of segment a–b within kMaxRange of the sensor and inside its
// field of view (a wedge of at most π about its x axis): a + t (b − a) for
// t in [lo, hi]; empty when hi <= lo.
struct Stretch {
  double lo = 0.0, hi = 0.0;
  double length(const Vector2& a, const Vector2& b) const {
    return hi > lo ? (hi - lo) * (b - a).norm() : 0.0;
  }
};
Stretch visibleStretch(const Pose2& sensor, const Vector2& a, const Vector2& b) {
  const Vector2 s = sensor.translation();
  const Vector2 u = b - a, w = a - s;
  double lo = 0.0, hi = 1.0;
  // The wedge: two half-planes c0 + c1 t >= 0.
  auto clip = [&](double c0, double c1) {
    if (std::abs(c1) < 1e-12) {
      if (c0 < 0.0) hi = -1.0;
      return;
    }
    const double t = -c0 / c1;
    if (c1 > 0.0) {
      lo = std::max(lo, t);
    } else {
      hi = std::min(hi, t);
    }
  };
  for (double side : {1.0, -1.0}) {
    // Inward normal of the edge at sensor.theta ± fov/2.
    const double edge = sensor.theta + side * kFieldOfView / 2.0;
    const Vector2 inward = side * Vector2(std::sin(edge), -std::cos(edge));
    clip(inward.dot(w), inward.dot(u));
  }
  // The disc: |w + t u|² <= R².
  const double qa = u.squaredNorm(), qb = 2.0 * w.dot(u),
               qc = w.squaredNorm() - kMaxRange * kMaxRange;
  const double disc = qb * qb - 4.0 * qa * qc;
  if (disc <= 0.0) return {};
  lo = std::max(lo, (-qb - std::sqrt(disc)) / (2.0 * qa));
  hi = std::min(hi, (-qb + std::sqrt(disc)) / (2.0 * qa));
  return {lo, hi};
}

// Whether the open segments p–q and a–b cross.
bool crosses(const Vector2& p, const Vector2& q, const Vector2& a, const Vector2& b) {
  auto side = [](const Vector2& o, const Vector2& d, const Vector2& x) {
    const Vector2 w = x - o;
    return d.x() * w.y() - d.y() * w.x();
  };
  const double s1 = side(p, q - p, a), s2 = side(p, q - p, b);
  const double s3 = side(a, b - a, p), s4 = side(a, b - a, q);
  return s1 * s2 < 0.0 && s3 * s4 < 0.0;
}

// Point `i` hidden from `sensor` by a wall it is not an end of.
bool occluded(const Vector2& sensor, int i) {
  for (const Wall& w : walls()) {
    if (w.end[0] == i || w.end[1] == i) continue;
    if (crosses(sensor, points()[i], points()[w.end[0]], points()[w.end[1]])) return true;
  }
  return false;
}

// The line through two points of the sensor frame given by their range
// and bearing, (r₁, φ₁, r₂, φ₂), in normal form with p >= 0.
PolarLine lineThrough(const Eigen::Vector4d& z) {
  const Vector2 q1 = z(0) * Vector2(std::cos(z(1)), std::sin(z(1)));
  const Vector2 q2 = z(2) * Vector2(std::cos(z(3)), std::sin(z(3)));
  const Vector2 d = (q2 - q1).normalized();
  Vector2 n(-d.y(), d.x());
  double p = n.dot(q1);
  if (p < 0.0) {
    n = -n;
    p = -p;
  }
  return PolarLine{p, std::atan2(n.y(), n.x())};
}

// A wall measured as the thesis measures it (eqs. 4.31-4.34): its two
// visible ends read with a point's range-bearing noise, the line through
// them, and its covariance T R Tᵀ, T = ∂(p, θ)/∂(r₁, φ₁, r₂, φ₂) (central
// differences at the readings, as the robot would have them).
LineObservation endpointLine(const Pose2& sensor, const Vector2& e1, const Vector2& e2,
                             double range_sigma, double bearing_sigma, std::mt19937* rng) {
  std::normal_distribution<double> unit;
  Eigen::Vector4d z;
  for (int k = 0; k < 2; ++k) {
    const Vector2 local = ekf_slam::transformTo(sensor, k == 0 ? e1 : e2);
    z(2 * k) = local.norm() + range_sigma * unit(*rng);
    z(2 * k + 1) = std::atan2(local.y(), local.x()) + bearing_sigma * unit(*rng);
  }
  const PolarLine line = lineThrough(z);
  Eigen::Matrix<double, 2, 4> T;
  for (int j = 0; j < 4; ++j) {
    const double h = 1e-6;
    Eigen::Vector4d plus = z, minus = z;
    plus(j) += h;
    minus(j) -= h;
    const PolarLine a = lineThrough(plus), b = lineThrough(minus);
    T(0, j) = (a.p - b.p) / (2 * h);
    T(1, j) = wrapAngle(a.theta - b.theta) / (2 * h);
  }
  const Eigen::Vector4d variances(range_sigma * range_sigma, bearing_sigma * bearing_sigma,
                                  range_sigma * range_sigma, bearing_sigma * bearing_sigma);
  LineObservation obs;
  obs.z = line;
  obs.covariance = T * variances.asDiagonal() * T.transpose();
  return obs;
}

enum class Variant {
  kPoints,
  kPThetaLines,
  kThetaLines,
  kThetaLinesNoEnds,
  kPoints360,
  kPointsMecp360
};
const Variant kVariants[] = {Variant::kPoints,     Variant::kPThetaLines,
                             Variant::kThetaLines, Variant::kThetaLinesNoEnds,
                             Variant::kPoints360,  Variant::kPointsMecp360};

bool usesMecp(Variant v) { return v == Variant::kPointsMecp360; }
double fieldOfView(Variant v) {
  return v == Variant::kPoints360 || v == Variant::kPointsMecp360 ? 2.0 * kPi : kFieldOfView;
}

const char* variantName(Variant v) {
  switch (v) {
    case Variant::kPoints:
      return "points";
    case Variant::kPThetaLines:
      return "ptheta_lines";
    case Variant::kThetaLines:
      return "theta_lines";
    case Variant::kThetaLinesNoEnds:
      return "theta_lines_no_ends";
    case Variant::kPoints360:
      return "points_360";
    case Variant::kPointsMecp360:
      return "points_mecp_360";
  }
  return "unknown";
}

// Per-step sums over runs; a feature error enters only where the run's map
// has that kind of feature.
struct StepStats {
  double pos = 0, heading = 0, nees = 0, point = 0, angle = 0, offset = 0;
  int point_runs = 0, angle_runs = 0, offset_runs = 0;
  double points_in_map = 0, lines_in_map = 0;
};

struct RunLog {
  std::vector<Vector2> truth, estimate;
};

// One run's own figures, for paired comparisons between variants (every
// variant sees the same draws of odometry and point noise for a seed).
struct RunSummary {
  double mean_pos = 0, final_pos = 0, mean_point = 0;
  long wrong = 0;       // point pairings with another feature's landmark (--association nn)
  long duplicates = 0;  // landmarks made from a feature that had one already (idem)
};

struct Refusals {
  long points = 0, lines = 0, augment = 0, predict = 0;
};

// What the MECP association did, over all scans of all runs.
struct MecpCounts {
  long polygons = 0, group_matches = 0, group_refused = 0, pairings_changed = 0, remembered = 0;
  void add(const ekf_slam::MecpCounters& c) {
    polygons += c.mecp_polygons;
    group_matches += c.mecp_group_matches;
    group_refused += c.mecp_group_refused;
    pairings_changed += c.mecp_pairings_changed;
    remembered += c.mecp_remembered;
  }
};

// Estimated offset of a line landmark: kLine its own p; kLineAngle the
// offset of the line with normal θ_f through the mean of its end points in
// the map (nan when none is).
double estimatedOffset(const EkfSlam& filter, int slot, const std::vector<int>& ends) {
  if (filter.landmarkKind(slot) == LandmarkKind::kLine) return filter.lineLandmark(slot).p;
  Vector2 sum = Vector2::Zero();
  int count = 0;
  for (int id : ends) {
    if (id < 0) continue;
    sum += filter.landmarkPosition(filter.slotOf(id));
    ++count;
  }
  if (count == 0) return kNan;
  const double theta = filter.lineAngle(slot);
  return Vector2(std::cos(theta), std::sin(theta)).dot(sum / count);
}

// |p error| of a line landmark's estimate against the wall, along a common
// normal (a normal estimated opposite to the true one flips the sign of p).
double offsetError(double theta_est, double p_est, const PolarLine& truth) {
  if (std::abs(wrapAngle(theta_est - truth.theta)) > kPi / 2.0) p_est = -p_est;
  return std::abs(p_est - truth.p);
}

void runOnce(Variant variant, const Conditions& conditions, unsigned seed, double noise_scale,
             std::vector<StepStats>* stats, RunLog* log, RunSummary* run, Refusals* refusals,
             MecpCounts* mecp, std::ofstream* map_out) {
  ekf_slam::sim::LandmarkSimOptions sim_options;
  sim_options.seed = seed;
  sim_options.landmarks = points();
  sim_options.waypoints = waypoints();
  sim_options.max_range = kMaxRange;
  sim_options.field_of_view = fieldOfView(variant);
  ekf_slam::scaleOdometryNoise(noise_scale, &sim_options.odometry_noise);
  ekf_slam::sim::LandmarkSimulator sim(sim_options);

  ekf_slam::FilterOptions options;
  options.laser_pose = sim_options.laser_pose;
  options.motion_noise = sim_options.odometry_noise;
  options.tentative_max_age = 0;  // known association: no landmark is spurious
  EkfSlam filter(options, sim.current().true_pose);

  const bool use_lines = variant == Variant::kPThetaLines || variant == Variant::kThetaLines ||
                         variant == Variant::kThetaLinesNoEnds;
  const LandmarkKind line_kind =
      variant == Variant::kPThetaLines ? LandmarkKind::kLine : LandmarkKind::kLineAngle;
  std::mt19937 line_rng(seed * 104729u + 17u);
  std::normal_distribution<double> unit;
  // point_id: the landmark made from each point feature first (scored);
  // feature_of: the feature each landmark was made from (duplicates under
  // nearest neighbour included).
  std::vector<int> point_id(points().size(), -1), line_id(walls().size(), -1);
  std::vector<int> feature_of;
  const ekf_slam::AssociationOptions association;
  ekf_slam::MecpAssociation mecp_association;
  Matrix2 line_noise = Matrix2::Zero();
  line_noise(0, 0) = kLinePSigma * kLinePSigma;
  line_noise(1, 1) = kLineThetaSigma * kLineThetaSigma;

  auto observe = [&](const ekf_slam::sim::SimStep& step) {
    // The points the sensor sees (walls hide some with --occlusion).
    const Vector2 sensor_at =
        ekf_slam::transformFrom(step.true_pose, sim_options.laser_pose.translation());
    std::vector<ekf_slam::PointObservation> seen;
    std::vector<int> feature;
    for (size_t i = 0; i < step.observations.size(); ++i) {
      if (conditions.occlusion && occluded(sensor_at, step.true_landmark[i])) continue;
      seen.push_back(step.observations[i]);
      feature.push_back(step.true_landmark[i]);
    }
    std::vector<PointMatch> matches;
    std::vector<int> fresh;
    if (conditions.nearest_neighbour || usesMecp(variant)) {
      const ekf_slam::AssociationResult result =
          usesMecp(variant) ? mecp_association.associate(filter, seen, association, nullptr)
                            : ekf_slam::associate(filter, seen, association);
      matches = result.matches();
      fresh = result.newLandmarks();
      for (const PointMatch& m : matches) {
        const int made_from =
            m.landmark_id < static_cast<int>(feature_of.size()) ? feature_of[m.landmark_id] : -1;
        if (made_from != feature[m.observation]) ++run->wrong;
      }
    } else {
      for (size_t i = 0; i < seen.size(); ++i) {
        const int id = point_id[feature[i]];
        if (id >= 0) {
          matches.push_back({static_cast<int>(i), id});
        } else {
          fresh.push_back(static_cast<int>(i));
        }
      }
    }
    if (!matches.empty() && filter.update(seen, matches) != FilterStatus::kOk) {
      ++refusals->points;
    }
    std::vector<int> landmark_of(seen.size(), -1);
    for (const PointMatch& m : matches) landmark_of[m.observation] = m.landmark_id;
    for (int i : fresh) {
      int id = -1;
      if (filter.augment(seen[i], &id) != FilterStatus::kOk) {
        ++refusals->augment;
        continue;
      }
      if (static_cast<int>(feature_of.size()) <= id) feature_of.resize(id + 1, -1);
      feature_of[id] = feature[i];
      if (point_id[feature[i]] < 0) {
        point_id[feature[i]] = id;
      } else {
        ++run->duplicates;
      }
      landmark_of[i] = id;
    }
    if (usesMecp(variant)) {
      ekf_slam::IterationReport report;
      report.matches = matches;
      for (int i : fresh) {
        if (landmark_of[i] >= 0) report.created.push_back({i, landmark_of[i]});
      }
      mecp_association.remember(filter, report);
    }
    if (!use_lines) return;
    const Pose2 sensor = ekf_slam::compose(step.true_pose, sim_options.laser_pose);
    std::vector<LineObservation> lines;
    std::vector<LineMatch> line_matches;
    for (size_t w = 0; w < walls().size(); ++w) {
      const Wall& wall = walls()[w];
      const Vector2 a = points()[wall.end[0]], b = points()[wall.end[1]];
      const Stretch visible = visibleStretch(sensor, a, b);
      if (visible.length(a, b) < kMinVisibleLength) continue;
      LineObservation obs;
      if (conditions.endpoint_lines) {
        obs = endpointLine(sensor, a + visible.lo * (b - a), a + visible.hi * (b - a),
                           sim_options.range_sigma, sim_options.bearing_sigma, &line_rng);
      } else {
        PolarLine z;
        if (!ekf_slam::predictLineObservation(step.true_pose, sim_options.laser_pose,
                                              wallLine(wall), &z)) {
          continue;
        }
        obs.covariance = line_noise;
        obs.z.p = z.p + kLinePSigma * unit(line_rng);
        obs.z.theta = wrapAngle(z.theta + kLineThetaSigma * unit(line_rng));
      }
      if (line_id[w] < 0) {
        if (filter.augmentLine(obs, line_kind, &line_id[w]) != FilterStatus::kOk) {
          ++refusals->augment;
        }
        continue;
      }
      lines.push_back(obs);
      LineMatch match{static_cast<int>(lines.size()) - 1, line_id[w]};
      if (variant == Variant::kThetaLines) {
        int count = 0;
        for (int e : wall.end) {
          if (point_id[e] >= 0) match.endpoint_ids[count++] = point_id[e];
        }
      }
      line_matches.push_back(match);
    }
    if (!line_matches.empty() && filter.updateLines(lines, line_matches) != FilterStatus::kOk) {
      ++refusals->lines;
    }
  };

  auto record = [&](size_t k, const ekf_slam::sim::SimStep& s) {
    if (stats->size() <= k) stats->resize(k + 1);
    StepStats& st = (*stats)[k];
    const Pose2 est = filter.pose();
    const double pos_err = std::hypot(est.x - s.true_pose.x, est.y - s.true_pose.y);
    st.pos += pos_err;
    run->mean_pos += pos_err;
    run->final_pos = pos_err;
    st.heading += std::abs(wrapAngle(est.theta - s.true_pose.theta));
    // Step 0's pose is known exactly (zero covariance): no NEES there.
    if (k > 0) st.nees += filter.poseNees(s.true_pose);
    double point_sum = 0, angle_sum = 0, offset_sum = 0;
    int point_count = 0, line_count = 0;
    for (size_t i = 0; i < point_id.size(); ++i) {
      if (point_id[i] < 0) continue;
      point_sum += (filter.landmarkPosition(filter.slotOf(point_id[i])) - points()[i]).norm();
      ++point_count;
    }
    for (size_t w = 0; w < line_id.size(); ++w) {
      if (line_id[w] < 0) continue;
      const int slot = filter.slotOf(line_id[w]);
      const PolarLine truth = wallLine(walls()[w]);
      const double theta = filter.landmarkKind(slot) == LandmarkKind::kLine
                               ? filter.lineLandmark(slot).theta
                               : filter.lineAngle(slot);
      angle_sum += std::abs(ekf_slam::lineAngleDifference(theta, truth.theta));
      if (filter.landmarkKind(slot) == LandmarkKind::kLine) {
        offset_sum += offsetError(theta, filter.lineLandmark(slot).p, truth);
      }
      ++line_count;
    }
    if (point_count > 0) {
      st.point += point_sum / point_count;
      run->mean_point += point_sum / point_count;
      ++st.point_runs;
    }
    if (line_count > 0) {
      st.angle += angle_sum / line_count;
      ++st.angle_runs;
      if (line_kind == LandmarkKind::kLine) {
        st.offset += offset_sum / line_count;
        ++st.offset_runs;
      }
    }
    st.points_in_map += point_count;
    st.lines_in_map += line_count;
    if (log) {
      log->truth.push_back(s.true_pose.translation());
      log->estimate.push_back(est.translation());
    }
  };

  observe(sim.current());
  record(0, sim.current());
  Pose2 odom = sim.current().odometry;
  size_t k = 0;
  while (true) {
    const Pose2 estimate = filter.pose();
    if (!sim.next(conditions.steer_by_estimate ? &estimate : nullptr)) break;
    const ekf_slam::sim::SimStep& s = sim.current();
    if (filter.predict(odom, s.odometry, sim_options.dt) != FilterStatus::kOk) ++refusals->predict;
    odom = s.odometry;
    observe(s);
    record(++k, s);
  }
  run->mean_pos /= k + 1;
  run->mean_point /= k + 1;
  mecp->add(mecp_association.counters());

  if (map_out) {
    for (size_t i = 0; i < point_id.size(); ++i) {
      if (point_id[i] < 0) continue;
      const Vector2 est = filter.landmarkPosition(filter.slotOf(point_id[i]));
      *map_out << "point " << i << ' ' << points()[i].x() << ' ' << points()[i].y() << ' '
               << est.x() << ' ' << est.y() << '\n';
    }
    for (size_t w = 0; w < line_id.size(); ++w) {
      if (line_id[w] < 0) continue;
      const int slot = filter.slotOf(line_id[w]);
      const PolarLine truth = wallLine(walls()[w]);
      const double theta = filter.landmarkKind(slot) == LandmarkKind::kLine
                               ? filter.lineLandmark(slot).theta
                               : filter.lineAngle(slot);
      std::vector<int> ends;
      if (variant == Variant::kThetaLines) {
        for (int e : walls()[w].end) ends.push_back(point_id[e]);
      }
      *map_out << "line " << w << ' ' << truth.theta << ' ' << truth.p << ' ' << theta << ' '
               << estimatedOffset(filter, slot, ends) << '\n';
    }
  }
}

double ratio(double sum, int count) { return count > 0 ? sum / count : kNan; }

}  // namespace

int main(int argc, char** argv) {
  ekf_slam::ExperimentOptions options;
  options.runs = 30;
  Conditions conditions;
  if (!takeConditions(&argc, argv, &conditions)) {
    std::cerr << "ekf_slam_line_experiment: --association takes nn or known, --line-noise "
                 "endpoints or gaussian\n";
    return 2;
  }
  if (!ekf_slam::parseExperimentOptions(argc, argv, "ekf_slam_line_experiment", &options)) return 2;
  const std::string& out_dir = options.out_dir;
  const int runs = options.runs;
  const unsigned first_seed = options.first_seed;
  const double noise_scale = options.noise_scale;
  const std::string dir = out_dir + "/";
  {
    std::ofstream world(dir + "world.txt");
    if (!world) {
      std::cerr << "ekf_slam_line_experiment: cannot write into " << out_dir << "\n";
      return 2;
    }
    world << "# wall x1 y1 x2 y2 | point x y (map frame, m)\n";
    for (const Wall& w : walls()) {
      const Vector2 a = points()[w.end[0]], b = points()[w.end[1]];
      world << "wall " << a.x() << ' ' << a.y() << ' ' << b.x() << ' ' << b.y() << '\n';
    }
    for (const Vector2& p : points()) world << "point " << p.x() << ' ' << p.y() << '\n';
  }

  const ekf_slam::ChiSquareBand band = ekf_slam::averageChiSquareBand(3, runs, 0.95);
  std::ofstream summary(dir + "summary.txt");
  summary << "# " << conditions.describe() << ", odometry noise x" << noise_scale << "\n"
          << "# variant runs steps mean_pos_err_m final_pos_err_m mean_heading_err_rad "
             "final_heading_err_rad average_nees band_lower band_upper steps_inside_band "
             "consistent mean_point_err_m final_point_err_m final_line_angle_err_rad "
             "refused_updates wrong_associations_per_run duplicate_landmarks_per_run\n";
  std::ofstream mecp_out(dir + "mecp.txt");
  mecp_out << "# variant scans_with_polygon group_matches group_refused pairings_changed "
              "polygons_remembered (sums over the runs)\n";
  std::ofstream per_run(dir + "runs.txt");
  per_run << "# variant seed mean_pos_err_m final_pos_err_m mean_point_err_m wrong_associations "
             "duplicate_landmarks\n";
  const double dt = ekf_slam::sim::LandmarkSimOptions().dt;
  for (Variant variant : kVariants) {
    const std::string name = variantName(variant);
    std::vector<StepStats> stats;
    Refusals refusals;
    MecpCounts mecp;
    long wrong = 0, duplicates = 0;
    RunLog log;
    std::ofstream map_out(dir + name + "_map.txt");
    map_out << "# point i x_true y_true x_est y_est | line i theta_true p_true theta_est p_est\n";
    for (int r = 0; r < runs; ++r) {
      RunSummary run;
      runOnce(variant, conditions, first_seed + r, noise_scale, &stats, r == 0 ? &log : nullptr,
              &run, &refusals, &mecp, r == 0 ? &map_out : nullptr);
      per_run << name << ' ' << first_seed + r << ' ' << run.mean_pos << ' ' << run.final_pos << ' '
              << run.mean_point << ' ' << run.wrong << ' ' << run.duplicates << '\n';
      wrong += run.wrong;
      duplicates += run.duplicates;
    }
    if (usesMecp(variant)) {
      mecp_out << name << ' ' << mecp.polygons << ' ' << mecp.group_matches << ' '
               << mecp.group_refused << ' ' << mecp.pairings_changed << ' ' << mecp.remembered
               << '\n';
    }
    std::ofstream path(dir + name + "_path.txt");
    path << "# step x_true y_true x_est y_est (run 0)\n";
    for (size_t k = 0; k < log.truth.size(); ++k) {
      path << k << ' ' << log.truth[k].x() << ' ' << log.truth[k].y() << ' ' << log.estimate[k].x()
           << ' ' << log.estimate[k].y() << '\n';
    }
    std::ofstream out(dir + name + ".txt");
    out << "# " << name << ", " << runs
        << " runs; means over runs. step time_s pos_err_m heading_err_rad nees point_err_m "
           "line_angle_err_rad line_p_err_m points_in_map lines_in_map\n";
    double pos_total = 0, heading_total = 0, nees_total = 0, point_total = 0;
    int inside = 0, point_steps = 0;
    for (size_t k = 0; k < stats.size(); ++k) {
      const StepStats& st = stats[k];
      const double nees = k > 0 ? st.nees / runs : kNan;
      out << k << ' ' << k * dt << ' ' << st.pos / runs << ' ' << st.heading / runs << ' ' << nees
          << ' ' << ratio(st.point, st.point_runs) << ' ' << ratio(st.angle, st.angle_runs) << ' '
          << ratio(st.offset, st.offset_runs) << ' ' << st.points_in_map / runs << ' '
          << st.lines_in_map / runs << '\n';
      pos_total += st.pos / runs;
      heading_total += st.heading / runs;
      if (k > 0) {
        nees_total += nees;
        if (nees >= band.lower && nees <= band.upper) ++inside;
      }
      if (st.point_runs > 0) {
        point_total += st.point / st.point_runs;
        ++point_steps;
      }
    }
    const size_t steps = stats.size();
    const StepStats& last = stats.back();
    const double average_nees = nees_total / (steps - 1);
    const bool consistent = average_nees >= band.lower && average_nees <= band.upper;
    char line[512];
    std::snprintf(
        line, sizeof line,
        "%s %d %zu %.4f %.4f %.5f %.5f %.3f %.3f %.3f %.3f %s %.4f %.4f %s %ld %.2f %.2f\n",
        name.c_str(), runs, steps, pos_total / steps, last.pos / runs, heading_total / steps,
        last.heading / runs, average_nees, band.lower, band.upper,
        static_cast<double>(inside) / (steps - 1), consistent ? "yes" : "no",
        point_total / std::max(point_steps, 1), ratio(last.point, last.point_runs),
        last.angle_runs > 0 ? std::to_string(last.angle / last.angle_runs).c_str() : "nan",
        refusals.points + refusals.lines + refusals.augment + refusals.predict,
        static_cast<double>(wrong) / runs, static_cast<double>(duplicates) / runs);
    summary << line;
    std::cout << line;
  }
  return 0;
}
