#include "ekf_slam_core/pose_graph/landmark_graph.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <optional>

namespace ekf_slam {

std::string LandmarkGraphOptions::validate() const { return checkFields(*this); }

Vector3 relativePoseError(const Pose2& from, const Pose2& to, const RelativePoseEdge& edge,
                          Matrix3* J_e_from, Matrix3* J_e_to) {
  Matrix3 J_a_from, J_b_to, J_r_a, J_r_b, J_e_r;
  const Pose2 a = compose(from, edge.from_offset, &J_a_from);
  const Pose2 b = compose(to, edge.to_offset, &J_b_to);
  const Pose2 relative = between(a, b, &J_r_a, &J_r_b);
  const Pose2 error = between(edge.measurement, relative, nullptr, &J_e_r);
  if (J_e_from) *J_e_from = J_e_r * J_r_a * J_a_from;
  if (J_e_to) *J_e_to = J_e_r * J_r_b * J_b_to;
  return error.vector();
}

bool observationError(const Pose2& robot, const Pose2& laser, const Vector2& landmark,
                      const RangeBearing& z, Vector2* e, Matrix23* J_e_robot,
                      Matrix2* J_e_landmark) {
  RangeBearing predicted;
  Matrix23 H_r;
  Matrix2 H_m;
  if (!predictPointObservation(robot, laser, landmark, &predicted, &H_r, &H_m)) return false;
  // e = z − h(x, m): the measurement is a constant, so the error moves
  // against the prediction.
  *e = Vector2(z.range - predicted.range, wrapAngle(z.bearing - predicted.bearing));
  if (J_e_robot) *J_e_robot = -H_r;
  if (J_e_landmark) *J_e_landmark = -H_m;
  return true;
}

int LandmarkGraph::addPose(const Pose2& pose, bool fixed) {
  poses_.push_back(pose);
  fixed_.push_back(fixed ? 1 : 0);
  return poseCount() - 1;
}

int LandmarkGraph::addLandmark(const Vector2& position) {
  landmarks_.push_back(position);
  return landmarkCount() - 1;
}

void LandmarkGraph::addEdge(const RelativePoseEdge& edge) {
  assert(edge.from >= 0 && edge.from < poseCount() && edge.to >= 0 && edge.to < poseCount());
  relatives_.push_back(edge);
}

void LandmarkGraph::addEdge(const PosePriorEdge& edge) {
  assert(edge.pose >= 0 && edge.pose < poseCount());
  priors_.push_back(edge);
}

void LandmarkGraph::addEdge(const ObservationEdge& edge) {
  assert(edge.pose >= 0 && edge.pose < poseCount());
  assert(edge.landmark >= 0 && edge.landmark < landmarkCount());
  observations_.push_back(edge);
}

double LandmarkGraph::cost(double kernel_width) const {
  return cost(poses_, landmarks_, kernel_width);
}

double LandmarkGraph::observationChi2(int index) const {
  const ObservationEdge& edge = observations_[index];
  Vector2 e;
  if (!observationError(poses_[edge.pose], laser_, landmarks_[edge.landmark], edge.z, &e)) {
    return 0.0;
  }
  return e.dot(edge.information * e);
}

double LandmarkGraph::cost(const std::vector<Pose2>& poses, const std::vector<Vector2>& landmarks,
                           double c) const {
  double total = 0.0;
  for (const RelativePoseEdge& edge : relatives_) {
    const Vector3 e = relativePoseError(poses[edge.from], poses[edge.to], edge);
    total += robustCost(edge.kernel, e.dot(edge.information * e), c);
  }
  for (const PosePriorEdge& edge : priors_) {
    Vector3 e = poses[edge.pose].vector() - edge.mean.vector();
    e(2) = wrapAngle(e(2));
    total += e.dot(edge.information * e);
  }
  for (const ObservationEdge& edge : observations_) {
    Vector2 e;
    if (!observationError(poses[edge.pose], laser_, landmarks[edge.landmark], edge.z, &e)) continue;
    total += robustCost(edge.kernel, e.dot(edge.information * e), c);
  }
  return total;
}

namespace {

// Accumulates the normal equations Σ w Jᵀ Ω J, Σ w Jᵀ Ω e over blocks whose
// unknowns start at the given offsets (−1: a fixed pose, no unknowns). H is
// kept as its lower triangle only: SimplicialLDLT (Lower) reads nothing
// else, and half the entries halve the assembly.
//
// The pattern of H is the same at every step of an optimisation, only its
// values change. The first assembly collects triplets and notes where each
// one lands in the compressed matrix (AssemblyPattern); later assemblies
// that add the same entries in the same order write straight into those
// slots of the same matrix. Each slot receives its contributions in the
// order setFromTriplets sums duplicates, so H is bit for bit the same
// either way.
struct AssemblyPattern {
  Eigen::SparseMatrix<double> H;  // compressed, every diagonal entry explicit
  std::vector<int> slot;          // per entry added: its index in H's values
};

class NormalEquations {
 public:
  // With `fill` null the entries are collected as triplets; otherwise they
  // are added into fill->H, zeroed first, in the order its slots were
  // recorded in (H is then assembled where it lives, with no copy).
  NormalEquations(int unknowns, size_t expected_entries, AssemblyPattern* fill)
      : b_(Eigen::VectorXd::Zero(unknowns)), fill_(fill) {
    if (fill_) {
      std::fill(fill_->H.valuePtr(), fill_->H.valuePtr() + fill_->H.nonZeros(), 0.0);
    } else {
      triplets_.reserve(expected_entries);
    }
  }

  template <typename JacobianA, typename JacobianB, typename Information, typename Error>
  void addPair(int offset_a, const JacobianA& J_a, int offset_b, const JacobianB& J_b,
               const Information& omega, const Error& e) {
    // Fixed-size products: no heap allocation per edge.
    const auto omega_a = (omega * J_a).eval();
    const auto omega_b = (omega * J_b).eval();
    addBlock(offset_a, offset_a, (J_a.transpose() * omega_a).eval());
    addBlock(offset_b, offset_b, (J_b.transpose() * omega_b).eval());
    const auto cross = (J_a.transpose() * omega_b).eval();
    addBlock(offset_a, offset_b, cross);
    addBlock(offset_b, offset_a, cross.transpose().eval());
    if (offset_a >= 0) b_.segment(offset_a, J_a.cols()) += J_a.transpose() * omega * e;
    if (offset_b >= 0) b_.segment(offset_b, J_b.cols()) += J_b.transpose() * omega * e;
  }

  template <typename Jacobian, typename Information, typename Error>
  void addSingle(int offset, const Jacobian& J, const Information& omega, const Error& e) {
    addBlock(offset, offset, (J.transpose() * omega * J).eval());
    if (offset >= 0) b_.segment(offset, J.cols()) += J.transpose() * omega * e;
  }

  // H with an explicit entry on every diagonal (an unknown no edge touches
  // stays regular), compressed, in pattern->H; from triplets the pattern's
  // slots are recorded too. Filling: false when the entries added were not
  // those of the pattern (then assemble afresh from triplets).
  bool finish(AssemblyPattern* pattern) {
    Eigen::SparseMatrix<double>& H = pattern->H;
    if (fill_) {
      if (added_ != fill_->slot.size() || mismatch_) return false;
      for (int k = 0; k < H.outerSize(); ++k) H.coeffRef(k, k) += 0.0;
      return true;
    }
    H.resize(b_.size(), b_.size());
    H.setFromTriplets(triplets_.begin(), triplets_.end());
    for (int k = 0; k < b_.size(); ++k) H.coeffRef(k, k) += 0.0;
    H.makeCompressed();
    pattern->slot.resize(triplets_.size());
    const int* outer = H.outerIndexPtr();
    const int* inner = H.innerIndexPtr();
    for (size_t t = 0; t < triplets_.size(); ++t) {
      const int col = triplets_[t].col();
      const int* at =
          std::lower_bound(inner + outer[col], inner + outer[col + 1], triplets_[t].row());
      pattern->slot[t] = static_cast<int>(at - inner);
    }
    triplets_ = {};
    return true;
  }
  const Eigen::VectorXd& gradient() const { return b_; }

 private:
  template <typename Block>
  void addBlock(int row, int col, const Block& block) {
    if (row < 0 || col < 0 || row + block.rows() - 1 < col) return;
    for (int i = 0; i < block.rows(); ++i) {
      for (int j = 0; j < block.cols(); ++j) {
        if (row + i < col + j) continue;
        if (!fill_) {
          triplets_.emplace_back(row + i, col + j, block(i, j));
        } else if (added_ < fill_->slot.size()) {
          // The slot must hold this very entry, or the edges differ.
          const int slot = fill_->slot[added_++];
          mismatch_ |= fill_->H.innerIndexPtr()[slot] != row + i;
          fill_->H.valuePtr()[slot] += block(i, j);
        } else {
          mismatch_ = true;
        }
      }
    }
  }

  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::VectorXd b_;
  AssemblyPattern* fill_;
  size_t added_ = 0;
  bool mismatch_ = false;
};

}  // namespace

LandmarkGraphSummary LandmarkGraph::optimize(const LandmarkGraphOptions& options) {
  LandmarkGraphSummary summary;
  const double c = options.kernel_width;
  summary.initial_cost = summary.final_cost = cost(c);

  // Unknowns: the free poses (3 each), then the landmarks (2 each).
  std::vector<int> pose_offset(poses_.size(), -1);
  int unknowns = 0;
  for (int i = 0; i < poseCount(); ++i) {
    if (!fixed_[i]) {
      pose_offset[i] = unknowns;
      unknowns += 3;
    }
  }
  const int landmark_start = unknowns;
  unknowns += 2 * landmarkCount();
  auto landmarkOffset = [&](int j) { return landmark_start + 2 * j; };
  if (unknowns == 0) {
    summary.end = SolveEnd::kConverged;
    return summary;
  }

  Damping damping(options.initial_lambda);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  bool pattern_known = false;
  AssemblyPattern pattern;
  bool have_pattern = false;
  // The normal equations at the current estimate, into H and `normal`.
  auto assemble = [&](NormalEquations& normal) {
    for (const RelativePoseEdge& edge : relatives_) {
      Matrix3 J_from, J_to;
      const Vector3 e = relativePoseError(poses_[edge.from], poses_[edge.to], edge, &J_from, &J_to);
      const double w = robustWeight(edge.kernel, e.dot(edge.information * e), c);
      const Matrix3 omega = w * edge.information;
      normal.addPair(pose_offset[edge.from], J_from, pose_offset[edge.to], J_to, omega, e);
    }
    for (const PosePriorEdge& edge : priors_) {
      Vector3 e = poses_[edge.pose].vector() - edge.mean.vector();
      e(2) = wrapAngle(e(2));
      normal.addSingle(pose_offset[edge.pose], Matrix3::Identity(), edge.information, e);
    }
    for (const ObservationEdge& edge : observations_) {
      Vector2 e;
      Matrix23 J_pose;
      Matrix2 J_landmark;
      if (!observationError(poses_[edge.pose], laser_, landmarks_[edge.landmark], edge.z, &e,
                            &J_pose, &J_landmark)) {
        continue;
      }
      const double w = robustWeight(edge.kernel, e.dot(edge.information * e), c);
      const Matrix2 omega = w * edge.information;
      normal.addPair(pose_offset[edge.pose], J_pose, landmarkOffset(edge.landmark), J_landmark,
                     omega, e);
    }
  };
  const size_t expected_entries =
      36 * (relatives_.size() + priors_.size()) + 25 * observations_.size();
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    std::optional<NormalEquations> normal;
    normal.emplace(unknowns, expected_entries, have_pattern ? &pattern : nullptr);
    assemble(*normal);
    if (!normal->finish(&pattern)) {
      // An edge dropped out or came back (its error could not be formed):
      // a new pattern, analysed afresh.
      normal.emplace(unknowns, expected_entries, nullptr);
      assemble(*normal);
      normal->finish(&pattern);
      pattern_known = false;
    }
    have_pattern = true;
    const Eigen::SparseMatrix<double>& H = pattern.H;
    // The sparsity pattern of H is the same at every step (only values
    // change), so the ordering and symbolic factorisation are done once.
    if (!pattern_known) {
      solver.analyzePattern(H);
      pattern_known = true;
      ++summary.symbolic_analyses;
    }

    const double cost_before = summary.final_cost;
    std::vector<Pose2> poses;
    std::vector<Vector2> landmarks;
    const DampedStep step = levenbergMarquardtStep(
        H, normal->gradient(), cost_before, &damping, &solver, [&](const Eigen::VectorXd& delta) {
          poses = poses_;
          landmarks = landmarks_;
          for (int i = 0; i < poseCount(); ++i) {
            if (pose_offset[i] >= 0) {
              poses[i] = Pose2::fromVector(poses_[i].vector() + delta.segment<3>(pose_offset[i]));
            }
          }
          for (int j = 0; j < landmarkCount(); ++j) {
            landmarks[j] += delta.segment<2>(landmarkOffset(j));
          }
          return cost(poses, landmarks, c);
        });
    summary.iterations = iteration + 1;
    if (!step.improved) {
      summary.end = step.at_minimum ? SolveEnd::kConverged : SolveEnd::kStalled;
      break;
    }
    poses_ = std::move(poses);
    landmarks_ = std::move(landmarks);
    summary.final_cost = step.cost;
    if (step.largest_step < options.convergence_step ||
        cost_before - summary.final_cost < options.min_relative_decrease * summary.final_cost) {
      summary.end = SolveEnd::kConverged;
      break;
    }
  }
  return summary;
}

}  // namespace ekf_slam
