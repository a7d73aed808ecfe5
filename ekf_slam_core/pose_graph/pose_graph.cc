#include "ekf_slam_core/pose_graph/pose_graph.h"
#include "ekf_slam_core/pose_graph/levenberg_marquardt.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <cassert>
#include <cmath>

namespace ekf_slam {

std::string PoseGraphOptions::validate() const { return checkFields(*this); }

Vector3 edgeError(const Pose2& from, const Pose2& to, const Pose2& measurement, Matrix3* J_e_from,
                  Matrix3* J_e_to) {
  Matrix3 J_r_from, J_r_to, J_e_r;
  const Pose2 relative = between(from, to, &J_r_from, &J_r_to);
  const Pose2 error = between(measurement, relative, nullptr, &J_e_r);
  if (J_e_from) *J_e_from = J_e_r * J_r_from;
  if (J_e_to) *J_e_to = J_e_r * J_r_to;
  return error.vector();
}

namespace {

// Cauchy kernel on s = eᵀ Ω e with width c (in sigmas): ρ(s) and ρ'(s).

// Node 0 is fixed, so node i > 0 owns the unknowns 3 (i − 1) … 3 (i − 1) + 2.
int unknownIndex(int node) { return 3 * (node - 1); }

// Only the lower triangle of H is assembled: SimplicialLDLT (Lower) reads
// nothing else, and half the entries halve the assembly.
void addBlock(std::vector<Eigen::Triplet<double>>* triplets, int row_node, int col_node,
              const Matrix3& block) {
  if (row_node == 0 || col_node == 0 || row_node < col_node) return;
  const int r = unknownIndex(row_node), c = unknownIndex(col_node);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (r + i >= c + j) triplets->emplace_back(r + i, c + j, block(i, j));
    }
  }
}

}  // namespace

int PoseGraph::addNode(const Pose2& pose) {
  poses_.push_back(pose);
  return nodeCount() - 1;
}

int PoseGraph::addEdge(const PoseGraphEdge& edge) {
  assert(edge.from >= 0 && edge.from < nodeCount() && edge.to >= 0 && edge.to < nodeCount());
  edges_.push_back(edge);
  return static_cast<int>(edges_.size()) - 1;
}

double PoseGraph::edgeChi2(int index) const {
  const PoseGraphEdge& edge = edges_[index];
  const Vector3 e = edgeError(poses_[edge.from], poses_[edge.to], edge.measurement);
  return e.dot(edge.information * e);
}

double PoseGraph::edgeWeight(int index, double robust_kernel_width) const {
  return edges_[index].robust
             ? robustWeight(RobustKernel::kCauchy, edgeChi2(index), robust_kernel_width)
             : 1.0;
}

double PoseGraph::cost(const std::vector<Pose2>& poses, double kernel_width) const {
  double total = 0.0;
  for (const PoseGraphEdge& edge : edges_) {
    if (!edge.active) continue;
    const Vector3 e = edgeError(poses[edge.from], poses[edge.to], edge.measurement);
    const double s = e.dot(edge.information * e);
    total += edge.robust ? robustCost(RobustKernel::kCauchy, s, kernel_width) : s;
  }
  return total;
}

PoseGraphSummary PoseGraph::optimize(const PoseGraphOptions& options) {
  PoseGraphSummary summary;
  const double c = options.robust_kernel_width;
  summary.initial_cost = summary.final_cost = cost(poses_, c);
  const int unknowns = 3 * (nodeCount() - 1);
  if (unknowns <= 0) {
    summary.end = SolveEnd::kConverged;
    return summary;
  }
  Damping damping(options.initial_lambda);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  std::vector<Eigen::Triplet<double>> triplets;
  // The edges, and so H's pattern, stay the same through the iterations.
  bool analysed = false;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    // Normal equations at the current poses, weights frozen (IRLS).
    triplets.clear();
    triplets.reserve(edges_.size() * 36 + unknowns);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(unknowns);
    for (const PoseGraphEdge& edge : edges_) {
      if (!edge.active) continue;
      Matrix3 J_from, J_to;
      const Vector3 e =
          edgeError(poses_[edge.from], poses_[edge.to], edge.measurement, &J_from, &J_to);
      const double w =
          edge.robust ? robustWeight(RobustKernel::kCauchy, e.dot(edge.information * e), c) : 1.0;
      const Matrix3 omega = w * edge.information;
      addBlock(&triplets, edge.from, edge.from, J_from.transpose() * omega * J_from);
      addBlock(&triplets, edge.from, edge.to, J_from.transpose() * omega * J_to);
      addBlock(&triplets, edge.to, edge.from, J_to.transpose() * omega * J_from);
      addBlock(&triplets, edge.to, edge.to, J_to.transpose() * omega * J_to);
      if (edge.from != 0) b.segment<3>(unknownIndex(edge.from)) += J_from.transpose() * omega * e;
      if (edge.to != 0) b.segment<3>(unknownIndex(edge.to)) += J_to.transpose() * omega * e;
    }
    Eigen::SparseMatrix<double> H(unknowns, unknowns);
    H.setFromTriplets(triplets.begin(), triplets.end());
    if (!analysed) {
      solver.analyzePattern(H);
      analysed = true;
    }

    // Levenberg-Marquardt: a step that does not raise the cost, or none.
    std::vector<Pose2> candidate;
    const DampedStep step = levenbergMarquardtStep(
        H, b, summary.final_cost, &damping, &solver, [&](const Eigen::VectorXd& delta) {
          candidate = poses_;
          for (int node = 1; node < nodeCount(); ++node) {
            candidate[node] =
                Pose2::fromVector(poses_[node].vector() + delta.segment<3>(unknownIndex(node)));
          }
          return cost(candidate, c);
        });
    summary.iterations = iteration + 1;
    if (!step.improved) {
      summary.end = step.at_minimum ? SolveEnd::kConverged : SolveEnd::kStalled;
      break;
    }
    poses_ = std::move(candidate);
    summary.final_cost = step.cost;
    if (step.largest_step < options.convergence_step) {
      summary.end = SolveEnd::kConverged;
      break;
    }
  }
  return summary;
}

}  // namespace ekf_slam
