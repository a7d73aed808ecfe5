#include "ekf_slam_core/smoother/full_smoother.h"

#include "ekf_slam_core/filter/chi_square.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

namespace ekf_slam {
namespace {

// Floor on the motion edge's covariance: (0.1 mm)² and (10 µrad)². The
// filter's model has no lateral noise for a turn on the spot (G₀ is
// singular when trans = 0); the floor keeps the information finite. It has
// to stay below the smallest real per-step variance: the simulator's
// random walk has 10⁻⁸ m² per step, and a (1 mm)² floor loosened the chain
// enough to make the smoothed office loop 3× worse (measured).
constexpr double kMotionFloorTranslation = 1e-8;  // m²
constexpr double kMotionFloorRotation = 1e-10;    // rad²

// A step's length for the wheels' random walk.
double wheelStepLength(const Pose2& step) {
  return std::max(std::hypot(step.x, step.y), kWheelMinStep);
}

// The wheels' disagreement with the motion edge's measurement over a step,
// when there is one: then the step has something to learn and a second
// edge to add. Where the match fell back to the wheels the two differ by
// rounding only (the increment went through the matcher's pose and back).
std::optional<Pose2> wheelDisagreement(const SmootherIteration& it) {
  constexpr double kSame = 1e-9;  // m, rad
  if (!it.has_control || !it.has_wheels) return std::nullopt;
  const Pose2 r = between(it.wheels, it.motion);
  if (std::abs(r.x) <= kSame && std::abs(r.y) <= kSame && std::abs(r.theta) <= kSame) {
    return std::nullopt;
  }
  return r;
}

bool isPositiveDefinite(const Matrix3& m) {
  const Eigen::LLT<Matrix3> llt(m);
  return m.allFinite() && llt.info() == Eigen::Success &&
         llt.matrixLLT().diagonal().minCoeff() > 0.0;
}

}  // namespace

std::string FullSmootherOptions::validate() const { return checkFields(*this); }

void FullSmootherRecorder::setPrior(const Pose2& mean, const Matrix3& covariance) {
  prior_mean_ = mean;
  prior_covariance_ = covariance;
}

void FullSmootherRecorder::restore(std::vector<SmootherIteration> iterations,
                                   std::unordered_map<int, int> merged_into,
                                   std::unordered_map<int, Vector2> last_estimates,
                                   const Pose2& prior_mean, const Matrix3& prior_covariance) {
  iterations_ = std::move(iterations);
  merged_into_ = std::move(merged_into);
  last_estimate_ = std::move(last_estimates);
  setPrior(prior_mean, prior_covariance);
}

void FullSmootherRecorder::addIteration(double stamp, const EkfSlam& filter,
                                        const OdometryControl* control,
                                        const std::vector<PointObservation>& observations,
                                        const IterationReport& report, const Pose2* local_motion,
                                        const Pose2* wheels) {
  SmootherIteration it;
  it.stamp = stamp;
  it.filtered = filter.pose();
  if (control != nullptr) {
    it.has_control = true;
    it.control = *control;
    it.control_covariance = controlCovariance(*control, filter.options().motion_noise);
    it.motion = local_motion != nullptr ? *local_motion : applyControl(Pose2(), *control);
    if (wheels != nullptr) {
      it.has_wheels = true;
      it.wheels = *wheels;
    }
  }
  // The update refuses as a whole, and then report.matches is empty: only
  // what the filter really used enters.
  for (const PointMatch& m : report.matches) {
    it.sightings.push_back({m.landmark_id, observations[m.observation]});
  }
  for (const PointMatch& m : report.created) {
    it.sightings.push_back({m.landmark_id, observations[m.observation]});
  }
  for (const auto& pair : report.merged) merged_into_[pair.second] = pair.first;
  // Landmarks removed later (pruned, merged away) keep the estimate they had
  // when last seen, for the initial guess.
  for (const LandmarkSighting& s : it.sightings) {
    const int slot = filter.slotOf(s.landmark_id);
    if (slot >= 0) last_estimate_[s.landmark_id] = filter.landmarkPosition(slot);
  }
  for (const auto& pair : report.merged) {
    const int slot = filter.slotOf(pair.first);
    if (slot >= 0) last_estimate_[pair.first] = filter.landmarkPosition(slot);
  }
  iterations_.push_back(std::move(it));
}

void FullSmootherRecorder::dropFront(size_t count) {
  count = std::min(count, iterations_.size());
  if (count == 0) return;
  iterations_.erase(iterations_.begin(), iterations_.begin() + count);
  // What the remaining sightings can still ask for: the merge chain of each
  // id they name, and the last estimate of every id on it. Later sightings
  // name landmarks the filter holds, whose merges are recorded as they come.
  std::unordered_map<int, int> merged_into;
  std::unordered_map<int, Vector2> last_estimate;
  auto keep = [&](int id) {
    const auto estimate = last_estimate_.find(id);
    if (estimate != last_estimate_.end()) last_estimate.insert(*estimate);
  };
  for (const SmootherIteration& it : iterations_) {
    for (const LandmarkSighting& s : it.sightings) {
      int id = s.landmark_id;
      keep(id);
      for (auto next = merged_into_.find(id); next != merged_into_.end();
           next = merged_into_.find(id)) {
        if (!merged_into.insert(*next).second) break;  // this chain is kept already
        id = next->second;
        keep(id);
      }
    }
  }
  merged_into_ = std::move(merged_into);
  last_estimate_ = std::move(last_estimate);
}

int FullSmootherRecorder::survivorOf(int id) const {
  // Merges form chains (a into b, later b into c); follow them to the end.
  for (auto it = merged_into_.find(id); it != merged_into_.end(); it = merged_into_.find(id)) {
    id = it->second;
  }
  return id;
}

WheelNoise learnWheelNoise(const std::vector<SmootherIteration>& iterations) {
  WheelNoise out;
  std::vector<double> per_metre[3];
  for (const SmootherIteration& it : iterations) {
    const std::optional<Pose2> r = wheelDisagreement(it);
    if (!r) continue;
    const double d = wheelStepLength(it.wheels);
    per_metre[0].push_back(r->x * r->x / d);
    per_metre[1].push_back(r->y * r->y / d);
    per_metre[2].push_back(r->theta * r->theta / d);
  }
  out.samples = static_cast<int>(per_metre[0].size());
  if (out.samples < kWheelMinSamples) return out;
  // The median of χ²₁ (a squared standard normal).
  constexpr double kMedianChiSquare1 = 0.454936;
  for (int i = 0; i < 3; ++i) {
    std::vector<double>& q = per_metre[i];
    std::nth_element(q.begin(), q.begin() + q.size() / 2, q.end());
    out.sigma_per_sqrt_metre[i] = std::sqrt(q[q.size() / 2] / kMedianChiSquare1);
  }
  return out;
}

Matrix3 motionEdgeCovariance(const OdometryControl& u, const Matrix3& control_covariance) {
  Matrix3 G0;
  const Pose2 d = applyControl(Pose2(), u, nullptr, &G0);
  Matrix3 A = Matrix3::Identity();
  A.topLeftCorner<2, 2>() = d.rotation().transpose();
  Matrix3 sigma = A * G0 * control_covariance * G0.transpose() * A.transpose();
  sigma = 0.5 * (sigma + sigma.transpose()).eval();
  sigma.diagonal() +=
      Vector3(kMotionFloorTranslation, kMotionFloorTranslation, kMotionFloorRotation);
  return sigma;
}

namespace {

// A landmark's sightings in iteration order, cut where it was not seen for
// more than `revisit_gap` iterations: each piece is one visit.
struct Track {
  int landmark_id = -1;                        // surviving id
  std::vector<std::pair<int, int>> sightings;  // (iteration, index into its sightings)
};

// Tracks that share a landmark node.
using Group = std::vector<int>;

struct Problem {
  LandmarkGraph graph;
  std::vector<std::vector<int>> edges_of_track;  // observation edge indices per track
  explicit Problem(const Pose2& laser) : graph(laser) {}
};

// A landmark of the re-association: the information-weighted mean of its
// sightings' map positions (their observation noise only: the pose error is
// shared by consecutive sightings and does not average out).
struct Cluster {
  Matrix2 information = Matrix2::Zero();
  Vector2 information_mean = Vector2::Zero();
  Vector2 mean = Vector2::Zero();
  long cell = 0;
};

// Spatial hash of the clusters' means, 1 m cells.
class ClusterGrid {
 public:
  static constexpr double kCell = 1.0;  // m
  static long key(long ix, long iy) { return ix * 1000003L + iy; }
  static long cellOf(const Vector2& p) {
    return key(static_cast<long>(std::floor(p.x() / kCell)),
               static_cast<long>(std::floor(p.y() / kCell)));
  }
  void insert(int id, long cell) { cells_[cell].push_back(id); }
  void move(int id, long from, long to) {
    if (from == to) return;
    std::vector<int>& old = cells_[from];
    old.erase(std::find(old.begin(), old.end(), id));
    insert(id, to);
  }
  // Clusters in the 3 × 3 cells around p.
  void near(const Vector2& p, std::vector<int>* out) const {
    out->clear();
    const long ix = static_cast<long>(std::floor(p.x() / kCell));
    const long iy = static_cast<long>(std::floor(p.y() / kCell));
    for (long dx = -1; dx <= 1; ++dx) {
      for (long dy = -1; dy <= 1; ++dy) {
        const auto it = cells_.find(key(ix + dx, iy + dy));
        if (it != cells_.end()) out->insert(out->end(), it->second.begin(), it->second.end());
      }
    }
  }

 private:
  std::unordered_map<long, std::vector<int>> cells_;
};

// Associates every sighting afresh against the map built from `poses`
// (FullSmootherOptions::reassociate): ids[k][i] is the new landmark of
// sighting i of iteration k, or −1 when it was left out.
std::vector<std::vector<int>> reassociate(const std::vector<SmootherIteration>& iterations,
                                          const std::vector<Pose2>& poses, const Pose2& laser,
                                          const FullSmootherOptions& options, int* ambiguous) {
  const double gate = chiSquareQuantile(options.reassociation_gate_probability, 2.0);
  const Vector3 pose_sigma(options.reassociation_position_sigma,
                           options.reassociation_position_sigma,
                           options.reassociation_heading_sigma);
  const Matrix3 pose_covariance = pose_sigma.cwiseAbs2().asDiagonal();
  std::vector<Cluster> clusters;
  ClusterGrid grid;
  std::vector<std::vector<int>> ids(iterations.size());
  std::vector<int> nearby;
  struct Candidate {
    double d2;
    int sighting;
    int cluster;
  };
  *ambiguous = 0;
  for (size_t k = 0; k < iterations.size(); ++k) {
    const std::vector<LandmarkSighting>& sightings = iterations[k].sightings;
    const int m = static_cast<int>(sightings.size());
    std::vector<Vector2> position(m);
    std::vector<Matrix2> noise(m);  // observation part of the position's covariance
    std::vector<Candidate> candidates;
    std::vector<int> candidate_count(m, 0);
    for (int i = 0; i < m; ++i) {
      Matrix23 G_robot;
      Matrix2 G_z;
      position[i] =
          landmarkFromObservation(poses[k], laser, sightings[i].observation.z, &G_robot, &G_z);
      noise[i] = G_z * sightings[i].observation.covariance * G_z.transpose();
      // The sighting and the landmark both carry the pose error here.
      const Matrix2 pose_part = G_robot * pose_covariance * G_robot.transpose();
      grid.near(position[i], &nearby);
      for (int c : nearby) {
        const Matrix2 S = noise[i] + 2.0 * pose_part + clusters[c].information.inverse();
        const Vector2 v = position[i] - clusters[c].mean;
        const double d2 = v.dot(S.ldlt().solve(v));
        if (d2 <= gate) {
          candidates.push_back({d2, i, c});
          ++candidate_count[i];
        }
      }
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return a.d2 != b.d2               ? a.d2 < b.d2
             : a.sighting != b.sighting ? a.sighting < b.sighting
                                        : a.cluster < b.cluster;
    });
    ids[k].assign(m, -1);
    std::unordered_map<int, char> taken;
    for (const Candidate& c : candidates) {
      if (candidate_count[c.sighting] > 1 || ids[k][c.sighting] >= 0 || taken[c.cluster]) continue;
      ids[k][c.sighting] = c.cluster;
      taken[c.cluster] = 1;
    }
    for (int i = 0; i < m; ++i) {
      if (candidate_count[i] > 1) {
        ++*ambiguous;
        continue;
      }
      if (ids[k][i] < 0 && candidate_count[i] == 0) {
        ids[k][i] = static_cast<int>(clusters.size());
        clusters.emplace_back();
        clusters.back().cell = ClusterGrid::cellOf(position[i]);
        grid.insert(ids[k][i], clusters.back().cell);
      }
      if (ids[k][i] < 0) continue;  // its only landmark took another sighting
      Cluster& cluster = clusters[ids[k][i]];
      const Matrix2 information = noise[i].inverse();
      cluster.information += information;
      cluster.information_mean += information * position[i];
      cluster.mean = cluster.information.ldlt().solve(cluster.information_mean);
      const long cell = ClusterGrid::cellOf(cluster.mean);
      grid.move(ids[k][i], cluster.cell, cell);
      cluster.cell = cell;
    }
  }
  return ids;
}

}  // namespace

FullSmootherResult smoothFull(const FullSmootherRecorder& record, const EkfSlam& filter,
                              const std::vector<IterationConstraint>& constraints,
                              const FullSmootherOptions& options,
                              const std::vector<Pose2>* initial_poses,
                              LandmarkGraph* last_problem) {
  FullSmootherResult result;
  const std::vector<SmootherIteration>& iterations = record.iterations();
  if (iterations.empty()) return result;
  const int n = static_cast<int>(iterations.size());

  const bool have_initial =
      initial_poses != nullptr && static_cast<int>(initial_poses->size()) == n;
  std::vector<std::vector<int>> new_ids;
  if (have_initial && options.reassociate) {
    new_ids = reassociate(iterations, *initial_poses, filter.options().laser_pose, options,
                          &result.ambiguous_sightings);
    result.reassociated = true;
  }

  // Tracks per surviving landmark (merges applied), or per new landmark.
  std::unordered_map<int, std::vector<int>> tracks_of;
  std::vector<Track> tracks;
  std::vector<int> order;  // landmark ids in order of first sighting (deterministic)
  for (int k = 0; k < n; ++k) {
    const std::vector<LandmarkSighting>& sightings = iterations[k].sightings;
    for (int i = 0; i < static_cast<int>(sightings.size()); ++i) {
      const int id =
          result.reassociated ? new_ids[k][i] : record.survivorOf(sightings[i].landmark_id);
      if (id < 0) continue;
      std::vector<int>& mine = tracks_of[id];
      if (mine.empty()) order.push_back(id);
      if (mine.empty() || k - tracks[mine.back()].sightings.back().first > options.revisit_gap) {
        mine.push_back(static_cast<int>(tracks.size()));
        tracks.push_back({id, {}});
      }
      tracks[mine.back()].sightings.emplace_back(k, i);
    }
  }
  // One group per landmark to begin with: the filter's associations.
  std::vector<Group> groups;
  std::vector<Vector2> group_position;
  for (int id : order) {
    const std::vector<int>& mine = tracks_of[id];
    size_t count = 0;
    for (int t : mine) count += tracks[t].sightings.size();
    // A landmark seen once adds no information on the poses (its two
    // unknowns absorb its two equations exactly): left out.
    if (count < 2) continue;
    groups.push_back(mine);
    if (have_initial) {
      group_position.emplace_back(Vector2::Zero());  // set from the initial poses below
      continue;
    }
    const int slot = filter.slotOf(id);
    const auto last = record.lastEstimates().find(id);
    group_position.push_back(slot >= 0                              ? filter.landmarkPosition(slot)
                             : last != record.lastEstimates().end() ? last->second
                                                                    : Vector2(Vector2::Zero()));
  }

  const bool prior_is_proper = isPositiveDefinite(record.priorCovariance());
  std::vector<Pose2> poses;
  for (const SmootherIteration& it : iterations) poses.push_back(it.filtered);
  if (have_initial) {
    poses = *initial_poses;
    // The filter's landmark estimates belong to the filtered poses: start
    // each landmark where its sightings put it from the new poses (the
    // median per coordinate, so a few wrong associations do not drag it).
    for (size_t g = 0; g < groups.size(); ++g) {
      std::vector<double> xs, ys;
      for (int t : groups[g]) {
        for (const auto& [k, i] : tracks[t].sightings) {
          const Vector2 m = landmarkFromObservation(poses[k], filter.options().laser_pose,
                                                    iterations[k].sightings[i].observation.z);
          xs.push_back(m.x());
          ys.push_back(m.y());
        }
      }
      std::nth_element(xs.begin(), xs.begin() + xs.size() / 2, xs.end());
      std::nth_element(ys.begin(), ys.begin() + ys.size() / 2, ys.end());
      group_position[g] = Vector2(xs[xs.size() / 2], ys[ys.size() / 2]);
    }
  }

  const WheelNoise wheels = options.wheel_edges ? learnWheelNoise(iterations) : WheelNoise();
  const bool wheel_edges = options.wheel_edges && wheels.samples >= kWheelMinSamples;
  result.wheels = wheels;

  auto build = [&](Problem* problem) {
    LandmarkGraph& graph = problem->graph;
    for (int k = 0; k < n; ++k) {
      // Zero prior covariance (the map frame is the first pose): hold it fixed.
      graph.addPose(poses[k], k == 0 && !prior_is_proper);
    }
    if (prior_is_proper) {
      PosePriorEdge prior;
      prior.pose = 0;
      prior.mean = record.priorMean();
      prior.information = record.priorCovariance().inverse();
      graph.addEdge(prior);
    }
    result.wheels.edges = 0;
    for (int k = 1; k < n; ++k) {
      const SmootherIteration& it = iterations[k];
      if (!it.has_control) continue;
      RelativePoseEdge motion;
      motion.from = k - 1;
      motion.to = k;
      motion.measurement = it.motion;
      motion.information = motionEdgeCovariance(it.control, it.control_covariance).inverse();
      graph.addEdge(motion);
      if (wheel_edges && wheelDisagreement(it)) {
        RelativePoseEdge wheel;
        wheel.from = k - 1;
        wheel.to = k;
        wheel.measurement = it.wheels;
        const Vector3 variance =
            wheels.sigma_per_sqrt_metre.cwiseAbs2() * wheelStepLength(it.wheels) +
            Vector3(kMotionFloorTranslation, kMotionFloorTranslation, kMotionFloorRotation);
        wheel.information = variance.cwiseInverse().asDiagonal();
        wheel.kernel = options.wheel_kernel;
        graph.addEdge(wheel);
        ++result.wheels.edges;
      }
    }
    problem->edges_of_track.assign(tracks.size(), {});
    int edge_index = 0;
    for (size_t g = 0; g < groups.size(); ++g) {
      const int node = graph.addLandmark(group_position[g]);
      for (int t : groups[g]) {
        for (const auto& [k, i] : tracks[t].sightings) {
          const PointObservation& obs = iterations[k].sightings[i].observation;
          ObservationEdge edge;
          edge.pose = k;
          edge.landmark = node;
          edge.z = obs.z;
          edge.information = obs.covariance.inverse();
          edge.kernel = options.observation_kernel;
          graph.addEdge(edge);
          problem->edges_of_track[t].push_back(edge_index++);
        }
      }
    }
    result.constraint_edges = 0;
    for (const IterationConstraint& c : constraints) {
      if (c.from_iteration < 0 || c.from_iteration >= n || c.to_iteration < 0 ||
          c.to_iteration >= n) {
        continue;
      }
      RelativePoseEdge edge;
      edge.from = c.from_iteration;
      edge.to = c.to_iteration;
      edge.from_offset = c.from_offset;
      edge.to_offset = c.to_offset;
      edge.measurement = c.measurement;
      edge.information = c.information;
      edge.kernel = options.loop_kernel;
      graph.addEdge(edge);
      ++result.constraint_edges;
    }
    result.observation_edges = edge_index;
  };

  std::unique_ptr<Problem> problem;
  // Solves that a verification follows stop at the looser tolerance; the
  // last one (the verification rounds spent, or nothing detached) runs to
  // the optimizer's own, from where the previous solve stopped.
  bool last_solve =
      options.verification_relative_decrease <= options.optimizer.min_relative_decrease;
  for (int round = 0;; ++round) {
    problem = std::make_unique<Problem>(filter.options().laser_pose);
    build(problem.get());
    if (last_problem) *last_problem = problem->graph;
    last_solve = last_solve || round >= options.max_verification_rounds;
    LandmarkGraphOptions solve_options = options.optimizer;
    if (!last_solve) solve_options.min_relative_decrease = options.verification_relative_decrease;
    const LandmarkGraphSummary summary = problem->graph.optimize(solve_options);
    if (round == 0) result.summary.initial_cost = summary.initial_cost;
    result.summary.iterations += summary.iterations;
    result.summary.final_cost = summary.final_cost;
    result.summary.end = summary.end;
    poses = problem->graph.poses();
    for (size_t g = 0; g < groups.size(); ++g) group_position[g] = problem->graph.landmarks()[g];
    if (round >= options.max_verification_rounds) break;

    // Verify the filter's re-associations: a visit whose sightings the
    // optimum cannot explain (their χ² beyond the gate for 2 per sighting)
    // belonged to another landmark. It is detached and becomes a landmark of
    // its own (or is dropped when it holds a single sighting), and the
    // problem is solved again.
    int detached = 0;
    const size_t group_count = groups.size();
    for (size_t g = 0; g < group_count; ++g) {
      if (groups[g].size() < 2) continue;
      std::vector<double> chi2(groups[g].size(), 0.0);
      std::vector<char> fails(groups[g].size(), 0);
      int best = 0;
      for (size_t j = 0; j < groups[g].size(); ++j) {
        const std::vector<int>& edges = problem->edges_of_track[groups[g][j]];
        for (int e : edges) chi2[j] += problem->graph.observationChi2(e);
        fails[j] = chi2[j] > chiSquareQuantile(options.revisit_gate_probability,
                                               2.0 * static_cast<double>(edges.size()));
        const double per = chi2[j] / edges.size();
        const double best_per = chi2[best] / problem->edges_of_track[groups[g][best]].size();
        if (per < best_per) best = static_cast<int>(j);
      }
      Group kept;
      for (size_t j = 0; j < groups[g].size(); ++j) {
        const int t = groups[g][j];
        if (!fails[j] || static_cast<int>(j) == best) {
          kept.push_back(t);
          continue;
        }
        ++detached;
        if (tracks[t].sightings.size() < 2) continue;
        const auto& [k, i] = tracks[t].sightings.front();
        groups.push_back({t});
        group_position.push_back(landmarkFromObservation(poses[k], filter.options().laser_pose,
                                                         iterations[k].sightings[i].observation.z));
      }
      groups[g] = kept;
    }
    result.detached_visits += detached;
    if (detached == 0) {
      if (last_solve) break;
      last_solve = true;  // the same problem once more, to the full tolerance
    }
  }

  result.poses = problem->graph.poses();
  for (size_t g = 0; g < groups.size(); ++g) {
    // A detached visit has no id of its own: only the landmark's first
    // group (which keeps the filter's id) is reported.
    const int id = tracks[groups[g].front()].landmark_id;
    if (result.landmarks.count(id) == 0) result.landmarks[id] = problem->graph.landmarks()[g];
  }
  return result;
}

}  // namespace ekf_slam
