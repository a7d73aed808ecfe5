// PoseGraph::optimize and LandmarkGraph::optimize with Ceres (options
// solver: ceres): Levenberg–Marquardt trust region over the cost functions
// of ceres_costs.h, sparse Cholesky of the normal equations, one thread.
// docs/solvers.md compares it with the hand-written solver on the real
// logs' problems.
#include <ceres/ceres.h>
#include <ceres/version.h>

#include <array>
#include <vector>

#include "ekf_slam_core/pose_graph/ceres_costs.h"
#include "ekf_slam_core/pose_graph/landmark_graph.h"
#include "ekf_slam_core/pose_graph/pose_graph.h"

namespace ekf_slam {
namespace {

// The sparse Cholesky: CXSparse's simplicial factorisation where this Ceres
// has it, else SuiteSparse's CHOLMOD. These problems are long chains of
// poses with a few hundred landmarks; CHOLMOD's supernodal factorisation
// with Debian's reference BLAS spends more per solve on them (the Intel
// log's full smoother: 2.75-2.94 against 3.12-3.52 s, the same steps and
// the same trajectory to the last digit written; docs/solvers.md). Ceres
// 2.2 dropped CXSparse.
ceres::SparseLinearAlgebraLibraryType sparseLibrary() {
#if CERES_VERSION_MAJOR == 2 && CERES_VERSION_MINOR < 2
  if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::CX_SPARSE)) return ceres::CX_SPARSE;
#endif
  return ceres::SUITE_SPARSE;
}

ceres::Solver::Options solverOptions(int max_iterations, double function_tolerance,
                                     double initial_lambda) {
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.sparse_linear_algebra_library_type = sparseLibrary();
  options.max_num_iterations = max_iterations;
  options.function_tolerance = function_tolerance;
  // The same first damping: Ceres's LM adds diag(JᵀJ) / radius.
  if (initial_lambda > 0.0) options.initial_trust_region_radius = 1.0 / initial_lambda;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}

ceres::Problem::Options problemOptions() {
  ceres::Problem::Options options;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // ceres_costs::Kernels has them
  return options;
}

int stepsOf(const ceres::Solver::Summary& summary) {
  return summary.num_successful_steps + summary.num_unsuccessful_steps;
}

}  // namespace

namespace ceres_costs {

void addPoseGraph(const PoseGraph& graph, Kernels* kernels,
                  std::vector<std::array<double, 3>>* poses, ceres::Problem* problem) {
  std::vector<std::array<double, 3>>& x = *poses;
  for (const PoseGraphEdge& edge : graph.edges()) {
    if (!edge.active) continue;
    RelativePoseEdge relative;
    relative.measurement = edge.measurement;
    relative.information = edge.information;
    problem->AddResidualBlock(new RelativePoseCost(relative, true),
                              edge.robust ? kernels->of(RobustKernel::kCauchy) : nullptr,
                              x[edge.from].data(), x[edge.to].data());
  }
  if (problem->HasParameterBlock(x[0].data())) problem->SetParameterBlockConstant(x[0].data());
}

void addLandmarkGraph(const LandmarkGraph& graph, Kernels* kernels,
                      std::vector<std::array<double, 3>>* poses,
                      std::vector<std::array<double, 2>>* landmarks, ceres::Problem* problem) {
  std::vector<std::array<double, 3>>& x = *poses;
  std::vector<std::array<double, 2>>& m = *landmarks;
  for (const RelativePoseEdge& e : graph.relativeEdges()) {
    problem->AddResidualBlock(new RelativePoseCost(e, false), kernels->of(e.kernel),
                              x[e.from].data(), x[e.to].data());
  }
  for (const PosePriorEdge& e : graph.priorEdges()) {
    problem->AddResidualBlock(new PosePriorCost(e), nullptr, x[e.pose].data());
  }
  for (const ObservationEdge& e : graph.observationEdges()) {
    problem->AddResidualBlock(new ObservationCost(e, graph.laserPose()), kernels->of(e.kernel),
                              x[e.pose].data(), m[e.landmark].data());
  }
  for (int i = 0; i < graph.poseCount(); ++i) {
    if (graph.isFixed(i) && problem->HasParameterBlock(x[i].data())) {
      problem->SetParameterBlockConstant(x[i].data());
    }
  }
}

}  // namespace ceres_costs

PoseGraphSummary PoseGraph::optimizeWithCeres(const PoseGraphOptions& options) {
  PoseGraphSummary summary;
  summary.initial_cost = summary.final_cost = cost(poses_, options.robust_kernel_width);
  if (nodeCount() <= 1) {
    summary.converged = true;
    return summary;
  }
  std::vector<std::array<double, 3>> x(poses_.size());
  for (size_t i = 0; i < poses_.size(); ++i) x[i] = {poses_[i].x, poses_[i].y, poses_[i].theta};
  ceres_costs::Kernels kernels(options.robust_kernel_width);
  ceres::Problem problem(problemOptions());
  ceres_costs::addPoseGraph(*this, &kernels, &x, &problem);
  if (problem.NumResidualBlocks() == 0) {
    summary.converged = true;
    return summary;
  }
  ceres::Solver::Summary result;
  // Ceres's own stop: a step lowering the cost by less than 1e-6 of it.
  ceres::Solve(solverOptions(options.max_iterations, 1e-6, options.initial_lambda), &problem,
               &result);
  for (size_t i = 1; i < poses_.size(); ++i)
    poses_[i] = Pose2(x[i][0], x[i][1], wrapAngle(x[i][2]));
  summary.iterations = stepsOf(result);
  summary.final_cost = cost(poses_, options.robust_kernel_width);
  summary.converged = result.termination_type == ceres::CONVERGENCE;
  return summary;
}

LandmarkGraphSummary LandmarkGraph::optimizeWithCeres(const LandmarkGraphOptions& options) {
  LandmarkGraphSummary summary;
  summary.initial_cost = summary.final_cost = cost(options.kernel_width);
  std::vector<std::array<double, 3>> x(poses_.size());
  std::vector<std::array<double, 2>> m(landmarks_.size());
  for (size_t i = 0; i < poses_.size(); ++i) x[i] = {poses_[i].x, poses_[i].y, poses_[i].theta};
  for (size_t j = 0; j < landmarks_.size(); ++j) m[j] = {landmarks_[j].x(), landmarks_[j].y()};
  ceres_costs::Kernels kernels(options.kernel_width);
  ceres::Problem problem(problemOptions());
  ceres_costs::addLandmarkGraph(*this, &kernels, &x, &m, &problem);
  bool free_unknowns = false;
  for (auto& pose : x) {
    free_unknowns |=
        problem.HasParameterBlock(pose.data()) && !problem.IsParameterBlockConstant(pose.data());
  }
  for (auto& landmark : m) free_unknowns |= problem.HasParameterBlock(landmark.data());
  if (!free_unknowns) {
    summary.converged = true;
    return summary;
  }
  ceres::Solver::Summary result;
  ceres::Solve(
      solverOptions(options.max_iterations, options.min_relative_decrease, options.initial_lambda),
      &problem, &result);
  for (size_t i = 0; i < poses_.size(); ++i) {
    if (!fixed_[i]) poses_[i] = Pose2(x[i][0], x[i][1], wrapAngle(x[i][2]));
  }
  for (size_t j = 0; j < landmarks_.size(); ++j) landmarks_[j] = Vector2(m[j][0], m[j][1]);
  summary.iterations = stepsOf(result);
  summary.symbolic_analyses = 1;
  summary.final_cost = cost(options.kernel_width);
  summary.converged = result.termination_type == ceres::CONVERGENCE;
  return summary;
}

}  // namespace ekf_slam
