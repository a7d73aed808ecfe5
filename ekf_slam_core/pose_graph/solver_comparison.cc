// solver_comparison: one exported least-squares problem (graph_io.h) solved
// by this folder's Levenberg–Marquardt (PoseGraph::optimize or
// LandmarkGraph::optimize) and by Ceres on the very same residuals, kernels,
// fixed poses and starting values, for docs/solvers.md
// (tools/dev/solver_comparison.sh runs it on the real logs).
//
//   solver_comparison --pose-graph FILE | --landmark-graph FILE
//                     --scans FILE --out DIR [--repeats N]
//
// For each solver: one tab-separated line on stdout
//   solver  final_cost  iterations  seconds  trajectory_file  termination
// final_cost: every solution evaluated with the hand-written solver's own
// cost Σ ρ(eᵀ Ω e) (twice what Ceres calls the cost, ½ Σ ρ), so all rows
// are comparable; iterations: the hand-written solver's LM steps, Ceres's
// successful + unsuccessful steps; seconds: the best of N runs (default 3)
// from the same start, Ceres's problem construction included;
// trajectory_file: the solution as one pose per scan (the scan anchors
// placed on the solved nodes), in DIR, for evaluate_relations.
//
// Residuals for Ceres: r = S e with Sᵀ S = Ω (from the information's eigen-decomposition),
// e and its Jacobians from the hand-written code (edgeError,
// relativePoseError, observationError), headings plain parameters wrapped
// inside the error as the hand-written code does. Kernels: Ceres's
// CauchyLoss(c) and HuberLoss(c) are c² log(1 + s/c²) and the Huber ρ of
// levenberg_marquardt.h with the same c, so Σ ρ matches term for term.
#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "ekf_slam_core/io/trajectory_file.h"
#include "ekf_slam_core/pose_graph/graph_io.h"
#include "ekf_slam_core/testing/ceres_reference.h"

namespace ekf_slam {
namespace {

using Clock = std::chrono::steady_clock;

struct CeresVariant {
  std::string name;
  ceres::LinearSolverType linear_solver;
  ceres::SparseLinearAlgebraLibraryType library;
  // SPARSE_SCHUR: eliminate the landmarks (else Ceres picks an independent set)
  bool landmarks_first = false;
};

ceres::Solver::Options solverOptions(const CeresVariant& variant, double initial_lambda) {
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = variant.linear_solver;
  options.sparse_linear_algebra_library_type = variant.library;
  options.max_num_iterations = 100;
  // Ceres's defaults: stop when the cost falls by less than 1e-6 of itself
  // in a step (the full smoother's own rule), or on a tiny gradient or step.
  options.function_tolerance = 1e-6;
  options.gradient_tolerance = 1e-10;
  options.parameter_tolerance = 1e-8;
  // The same first damping: Ceres's LM adds diag(JᵀJ) / radius.
  if (initial_lambda > 0.0) options.initial_trust_region_radius = 1.0 / initial_lambda;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}

struct Outcome {
  std::string solver;
  double cost = 0.0;
  int iterations = 0;
  double seconds = 0.0;
  std::string termination;
  std::vector<Pose2> poses;
  std::vector<Vector2> landmarks;
};

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// ---- pose graph ----------------------------------------------------------

// PoseGraph's cost at the given poses (its own cost() is private).
double poseGraphCost(const PoseGraph& graph, const std::vector<Pose2>& poses, double c) {
  double total = 0.0;
  for (const PoseGraphEdge& edge : graph.edges()) {
    if (!edge.active) continue;
    const Vector3 e = edgeError(poses[edge.from], poses[edge.to], edge.measurement);
    const double s = e.dot(edge.information * e);
    total += edge.robust ? robustCost(RobustKernel::kCauchy, s, c) : s;
  }
  return total;
}

Outcome solvePoseGraphByHand(const PoseGraph& problem, const PoseGraphOptions& options,
                             const std::string& name, int repeats) {
  Outcome best;
  best.solver = name;
  for (int run = 0; run < repeats; ++run) {
    PoseGraph graph = problem;
    const auto start = Clock::now();
    const PoseGraphSummary summary = graph.optimize(options);
    const double seconds = secondsSince(start);
    if (run == 0 || seconds < best.seconds) best.seconds = seconds;
    best.iterations = summary.iterations;
    best.termination = solveEndName(summary.end);
    best.poses = graph.poses();
  }
  best.cost = poseGraphCost(problem, best.poses, options.robust_kernel_width);
  return best;
}

Outcome solvePoseGraphWithCeres(const PoseGraph& graph, const PoseGraphOptions& graph_options,
                                const CeresVariant& variant, int repeats) {
  Outcome best;
  best.solver = variant.name;
  for (int run = 0; run < repeats; ++run) {
    std::vector<std::array<double, 3>> x = ceres_costs::poseArrays(graph.poses());
    const auto start = Clock::now();
    ceres_costs::Kernels kernels(graph_options.robust_kernel_width);
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    ceres_costs::addPoseGraph(graph, &kernels, &x, &problem);
    ceres::Solver::Summary summary;
    ceres::Solve(solverOptions(variant, graph_options.initial_lambda), &problem, &summary);
    const double seconds = secondsSince(start);
    if (run == 0 || seconds < best.seconds) best.seconds = seconds;
    best.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
    best.termination = ceres::TerminationTypeToString(summary.termination_type);
    best.poses.clear();
    for (const auto& p : x) best.poses.emplace_back(p[0], p[1], p[2]);
  }
  best.cost = poseGraphCost(graph, best.poses, graph_options.robust_kernel_width);
  return best;
}

// ---- landmark graph ------------------------------------------------------

Outcome solveLandmarkGraphByHand(const LandmarkGraph& problem, const LandmarkGraphOptions& options,
                                 const std::string& name, int repeats) {
  Outcome best;
  best.solver = name;
  for (int run = 0; run < repeats; ++run) {
    LandmarkGraph graph = problem;
    const auto start = Clock::now();
    const LandmarkGraphSummary summary = graph.optimize(options);
    const double seconds = secondsSince(start);
    if (run == 0 || seconds < best.seconds) best.seconds = seconds;
    best.iterations = summary.iterations;
    best.termination = solveEndName(summary.end);
    best.poses = graph.poses();
    best.landmarks = graph.landmarks();
  }
  best.cost = withValues(problem, best.poses, best.landmarks).cost(options.kernel_width);
  return best;
}

Outcome solveLandmarkGraphWithCeres(const LandmarkGraph& graph,
                                    const LandmarkGraphOptions& graph_options,
                                    const CeresVariant& variant, int repeats) {
  Outcome best;
  best.solver = variant.name;
  for (int run = 0; run < repeats; ++run) {
    std::vector<std::array<double, 3>> x = ceres_costs::poseArrays(graph.poses());
    std::vector<std::array<double, 2>> m = ceres_costs::landmarkArrays(graph.landmarks());
    const auto start = Clock::now();
    ceres_costs::Kernels kernels(graph_options.kernel_width);
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    ceres_costs::addLandmarkGraph(graph, &kernels, &x, &m, &problem);
    ceres::Solver::Options options = solverOptions(variant, graph_options.initial_lambda);
    if (variant.landmarks_first) {
      auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
      for (auto& landmark : m) {
        if (problem.HasParameterBlock(landmark.data()))
          ordering->AddElementToGroup(landmark.data(), 0);
      }
      for (auto& pose : x) {
        if (problem.HasParameterBlock(pose.data())) ordering->AddElementToGroup(pose.data(), 1);
      }
      options.linear_solver_ordering = ordering;
    }
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    const double seconds = secondsSince(start);
    if (run == 0 || seconds < best.seconds) best.seconds = seconds;
    best.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
    best.termination = ceres::TerminationTypeToString(summary.termination_type);
    if (summary.termination_type == ceres::FAILURE) best.termination += ": " + summary.message;
    best.poses.clear();
    best.landmarks.clear();
    for (const auto& p : x) best.poses.emplace_back(p[0], p[1], p[2]);
    for (const auto& q : m) best.landmarks.emplace_back(q[0], q[1]);
  }
  best.cost = withValues(graph, best.poses, best.landmarks).cost(graph_options.kernel_width);
  return best;
}

// ---- output --------------------------------------------------------------

std::string fileNameOf(const std::string& solver) {
  std::string out;
  for (char ch : solver) {
    const bool keep =
        (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9');
    out += keep ? static_cast<char>(std::tolower(static_cast<unsigned char>(ch))) : '_';
  }
  return out;
}

bool report(const Outcome& o, const std::vector<ScanAnchor>& anchors, const std::string& out_dir,
            const std::string& prefix) {
  const std::string path = out_dir + "/trajectory_" + prefix + "_" + fileNameOf(o.solver) + ".txt";
  const std::string error = writeTrajectory(path, anchoredScanPoses(anchors, o.poses));
  if (!error.empty()) {
    std::cerr << "solver_comparison: " << error << "\n";
    return false;
  }
  std::printf("%s\t%.10g\t%d\t%.6f\t%s\t%s\n", o.solver.c_str(), o.cost, o.iterations, o.seconds,
              path.c_str(), o.termination.c_str());
  std::fflush(stdout);
  return true;
}

int usage() {
  std::cerr << "usage: solver_comparison (--pose-graph FILE | --landmark-graph FILE) --scans FILE "
               "--out DIR [--repeats N]\n";
  return 2;
}

}  // namespace
}  // namespace ekf_slam

int main(int argc, char** argv) {
  using namespace ekf_slam;
  std::string pose_graph_path, landmark_graph_path, scans_path, out_dir;
  int repeats = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--pose-graph" && i + 1 < argc) {
      pose_graph_path = argv[++i];
    } else if (arg == "--landmark-graph" && i + 1 < argc) {
      landmark_graph_path = argv[++i];
    } else if (arg == "--scans" && i + 1 < argc) {
      scans_path = argv[++i];
    } else if (arg == "--out" && i + 1 < argc) {
      out_dir = argv[++i];
    } else if (arg == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::atoi(argv[++i]));
    } else {
      return usage();
    }
  }
  if (pose_graph_path.empty() == landmark_graph_path.empty() || scans_path.empty() ||
      out_dir.empty()) {
    return usage();
  }
  std::vector<ScanAnchor> anchors;
  std::string error = loadScanAnchors(scans_path, &anchors);
  if (!error.empty()) {
    std::cerr << "solver_comparison: " << error << "\n";
    return 2;
  }
  const auto suitesparse = ceres::SUITE_SPARSE;
  const auto eigen = ceres::EIGEN_SPARSE;
  bool ok = true;
  if (!pose_graph_path.empty()) {
    PoseGraph graph;
    PoseGraphOptions options;
    error = loadPoseGraph(pose_graph_path, &graph, &options);
    if (!error.empty()) {
      std::cerr << "solver_comparison: " << error << "\n";
      return 2;
    }
    const Outcome as_run = solvePoseGraphByHand(graph, options, "hand-written LM", repeats);
    ok &= report(as_run, anchors, out_dir, "pose_graph");
    if (as_run.termination != "converged") {
      // Stopped by the back end's step cap: the same solver with ten times as many.
      PoseGraphOptions longer = options;
      longer.max_iterations *= 10;
      const std::string name =
          "hand-written LM, " + std::to_string(longer.max_iterations) + " steps";
      ok &= report(solvePoseGraphByHand(graph, longer, name, repeats), anchors, out_dir,
                   "pose_graph");
    }
    const CeresVariant variants[] = {
        {"Ceres SPARSE_NORMAL_CHOLESKY (SuiteSparse)", ceres::SPARSE_NORMAL_CHOLESKY, suitesparse},
        {"Ceres SPARSE_NORMAL_CHOLESKY (Eigen)", ceres::SPARSE_NORMAL_CHOLESKY, eigen},
        {"Ceres SPARSE_SCHUR (SuiteSparse), automatic ordering", ceres::SPARSE_SCHUR, suitesparse},
    };
    for (const CeresVariant& v : variants) {
      ok &= report(solvePoseGraphWithCeres(graph, options, v, repeats), anchors, out_dir,
                   "pose_graph");
    }
  } else {
    LandmarkGraph graph;
    LandmarkGraphOptions options;
    error = loadLandmarkGraph(landmark_graph_path, &graph, &options);
    if (!error.empty()) {
      std::cerr << "solver_comparison: " << error << "\n";
      return 2;
    }
    const Outcome as_run = solveLandmarkGraphByHand(graph, options, "hand-written LM", repeats);
    ok &= report(as_run, anchors, out_dir, "landmark_graph");
    if (as_run.termination != "converged") {
      // Stopped by the smoother's step cap: the same solver with ten times as many.
      LandmarkGraphOptions longer = options;
      longer.max_iterations *= 10;
      const std::string name =
          "hand-written LM, " + std::to_string(longer.max_iterations) + " steps";
      ok &= report(solveLandmarkGraphByHand(graph, longer, name, repeats), anchors, out_dir,
                   "landmark_graph");
    }
    const CeresVariant variants[] = {
        {"Ceres SPARSE_SCHUR (SuiteSparse), landmarks eliminated", ceres::SPARSE_SCHUR, suitesparse,
         true},
        {"Ceres SPARSE_SCHUR (SuiteSparse), automatic ordering", ceres::SPARSE_SCHUR, suitesparse},
        {"Ceres SPARSE_NORMAL_CHOLESKY (SuiteSparse)", ceres::SPARSE_NORMAL_CHOLESKY, suitesparse},
        {"Ceres SPARSE_NORMAL_CHOLESKY (Eigen)", ceres::SPARSE_NORMAL_CHOLESKY, eigen},
    };
    for (const CeresVariant& v : variants) {
      ok &= report(solveLandmarkGraphWithCeres(graph, options, v, repeats), anchors, out_dir,
                   "landmark_graph");
    }
  }
  return ok ? 0 : 1;
}
