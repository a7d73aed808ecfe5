// The reference solves of ceres_reference.h: Ceres's Levenberg–Marquardt
// trust region over the cost functions declared there, sparse Cholesky of
// the normal equations, one thread.
#include <ceres/ceres.h>
#include <ceres/version.h>

#include <array>
#include <vector>

#include "ekf_slam_core/testing/ceres_reference.h"

namespace ekf_slam {
namespace {

// The sparse Cholesky: CXSparse's simplicial factorisation where this Ceres
// has it (faster than CHOLMOD's supernodal one with Debian's reference BLAS
// on these long chains of poses), else SuiteSparse's CHOLMOD. Ceres 2.2
// dropped CXSparse.
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

std::vector<std::array<double, 3>> poseArrays(const std::vector<Pose2>& poses) {
  std::vector<std::array<double, 3>> x;
  x.reserve(poses.size());
  for (const Pose2& p : poses) x.push_back({p.x, p.y, p.theta});
  return x;
}

std::vector<std::array<double, 2>> landmarkArrays(const std::vector<Vector2>& landmarks) {
  std::vector<std::array<double, 2>> m;
  m.reserve(landmarks.size());
  for (const Vector2& l : landmarks) m.push_back({l.x(), l.y()});
  return m;
}

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

PoseGraph solveWithCeres(const PoseGraph& graph, const PoseGraphOptions& options,
                         double function_tolerance, PoseGraphSummary* summary) {
  PoseGraph solved = graph;
  PoseGraphSummary report;
  std::vector<std::array<double, 3>> x = ceres_costs::poseArrays(graph.poses());
  ceres_costs::Kernels kernels(options.robust_kernel_width);
  ceres::Problem problem(problemOptions());
  ceres_costs::addPoseGraph(graph, &kernels, &x, &problem);
  report.end = SolveEnd::kConverged;
  if (problem.NumResidualBlocks() > 0) {
    ceres::Solver::Summary result;
    ceres::Solve(solverOptions(options.max_iterations, function_tolerance, options.initial_lambda),
                 &problem, &result);
    for (int i = 1; i < graph.nodeCount(); ++i) {
      solved.setPose(i, Pose2(x[i][0], x[i][1], wrapAngle(x[i][2])));
    }
    report.iterations = stepsOf(result);
    report.end = result.termination_type == ceres::CONVERGENCE ? SolveEnd::kConverged
                                                               : SolveEnd::kIterationLimit;
  }
  // The hand-written cost Σ ρ(eᵀ Ω e) at both ends.
  auto cost = [&](const PoseGraph& g) {
    double total = 0.0;
    for (int e = 0; e < static_cast<int>(g.edges().size()); ++e) {
      if (!g.edges()[e].active) continue;
      const double s = g.edgeChi2(e);
      total += g.edges()[e].robust
                   ? robustCost(RobustKernel::kCauchy, s, options.robust_kernel_width)
                   : s;
    }
    return total;
  };
  report.initial_cost = cost(graph);
  report.final_cost = cost(solved);
  if (summary) *summary = report;
  return solved;
}

LandmarkGraph withValues(const LandmarkGraph& graph, const std::vector<Pose2>& poses,
                         const std::vector<Vector2>& landmarks) {
  LandmarkGraph out(graph.laserPose());
  for (int i = 0; i < graph.poseCount(); ++i) out.addPose(poses[i], graph.isFixed(i));
  for (const Vector2& m : landmarks) out.addLandmark(m);
  for (const RelativePoseEdge& e : graph.relativeEdges()) out.addEdge(e);
  for (const PosePriorEdge& e : graph.priorEdges()) out.addEdge(e);
  for (const ObservationEdge& e : graph.observationEdges()) out.addEdge(e);
  return out;
}

LandmarkGraph solveWithCeres(const LandmarkGraph& graph, const LandmarkGraphOptions& options,
                             LandmarkGraphSummary* summary) {
  LandmarkGraphSummary report;
  report.initial_cost = graph.cost(options.kernel_width);
  std::vector<std::array<double, 3>> x = ceres_costs::poseArrays(graph.poses());
  std::vector<std::array<double, 2>> m = ceres_costs::landmarkArrays(graph.landmarks());
  ceres_costs::Kernels kernels(options.kernel_width);
  ceres::Problem problem(problemOptions());
  ceres_costs::addLandmarkGraph(graph, &kernels, &x, &m, &problem);
  bool free_unknowns = false;
  for (auto& pose : x) {
    free_unknowns |=
        problem.HasParameterBlock(pose.data()) && !problem.IsParameterBlockConstant(pose.data());
  }
  for (auto& landmark : m) free_unknowns |= problem.HasParameterBlock(landmark.data());
  report.end = SolveEnd::kConverged;
  if (free_unknowns) {
    ceres::Solver::Summary result;
    ceres::Solve(solverOptions(options.max_iterations, options.min_relative_decrease,
                               options.initial_lambda),
                 &problem, &result);
    report.iterations = stepsOf(result);
    report.end = result.termination_type == ceres::CONVERGENCE ? SolveEnd::kConverged
                                                               : SolveEnd::kIterationLimit;
  }
  std::vector<Pose2> poses(graph.poses());
  std::vector<Vector2> landmarks(graph.landmarks());
  for (int i = 0; i < graph.poseCount(); ++i) {
    if (!graph.isFixed(i)) poses[i] = Pose2(x[i][0], x[i][1], wrapAngle(x[i][2]));
  }
  for (int j = 0; j < graph.landmarkCount(); ++j) landmarks[j] = Vector2(m[j][0], m[j][1]);
  LandmarkGraph solved = withValues(graph, poses, landmarks);
  report.symbolic_analyses = 1;
  report.final_cost = solved.cost(options.kernel_width);
  if (summary) *summary = report;
  return solved;
}

}  // namespace ekf_slam
