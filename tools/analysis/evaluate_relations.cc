// evaluate_relations: the relation metric of the Freiburg SLAM benchmark
// (../shared/datasets/README.md) for a trajectory file.
//
//   evaluate_relations --relations FILE --trajectory FILE [--tolerance S]
//                      [--allow-missing] [--label NAME] [--by-span]
//
// Prints mean ± std of the absolute translational (m) and rotational (deg)
// errors and of their squares, and the relations used. --by-span adds the
// means by the time between a relation's two poses (under 5 s, 5–30 s,
// 30–120 s, 120–300 s, 300 s and more) and each group's share of the
// summed translational error: the short groups show the local accuracy,
// the long ones whether revisits agree. Exit code 1 when a
// relation does not find its two poses (unless --allow-missing), 2 on usage
// or file errors.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "ekf_slam_core/eval/relations.h"

int main(int argc, char** argv) {
  std::string relations_path, trajectory_path, label = "trajectory";
  double tolerance = 1e-4;
  bool allow_missing = false, by_span = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--relations" && i + 1 < argc) {
      relations_path = argv[++i];
    } else if (arg == "--trajectory" && i + 1 < argc) {
      trajectory_path = argv[++i];
    } else if (arg == "--tolerance" && i + 1 < argc) {
      tolerance = std::atof(argv[++i]);
    } else if (arg == "--label" && i + 1 < argc) {
      label = argv[++i];
    } else if (arg == "--allow-missing") {
      allow_missing = true;
    } else if (arg == "--by-span") {
      by_span = true;
    } else {
      std::cerr << "usage: evaluate_relations --relations FILE --trajectory FILE [--tolerance S]"
                   " [--allow-missing] [--label NAME] [--by-span]\n";
      return 2;
    }
  }
  if (relations_path.empty() || trajectory_path.empty()) {
    std::cerr << "evaluate_relations: --relations and --trajectory are required\n";
    return 2;
  }
  std::vector<ekf_slam::Relation> relations;
  std::vector<ekf_slam::StampedPose> trajectory;
  std::string error = ekf_slam::readRelations(relations_path, &relations);
  if (error.empty()) error = ekf_slam::readTrajectory(trajectory_path, &trajectory);
  if (!error.empty()) {
    std::cerr << "evaluate_relations: " << error << "\n";
    return 2;
  }
  const ekf_slam::RelationErrors e = ekf_slam::evaluateRelations(relations, trajectory, tolerance);
  const double deg = 180.0 / ekf_slam::kPi;
  std::printf(
      "%s: relations used %d / %d\n"
      "  translation: %.4f +- %.4f m   (squared %.5f +- %.5f m^2)\n"
      "  rotation:    %.3f +- %.3f deg (squared %.4f +- %.4f deg^2)\n",
      label.c_str(), e.used, e.relations, e.translation.mean, e.translation.stddev,
      e.translation_squared.mean, e.translation_squared.stddev, e.rotation.mean * deg,
      e.rotation.stddev * deg, e.rotation_squared.mean * deg * deg,
      e.rotation_squared.stddev * deg * deg);
  if (by_span) {
    for (const ekf_slam::SpanBin& bin : ekf_slam::errorsBySpan(e, {0.0, 5.0, 30.0, 120.0, 300.0})) {
      const std::string range = std::isinf(bin.to)
                                    ? ">= " + std::to_string(static_cast<int>(bin.from)) + " s"
                                    : std::to_string(static_cast<int>(bin.from)) + "-" +
                                          std::to_string(static_cast<int>(bin.to)) + " s";
      std::printf("  span %-10s %5d relations  %.4f m  %.3f deg  (%.0f %% of the error)\n",
                  range.c_str(), bin.relations, bin.translation_mean, bin.rotation_mean * deg,
                  100.0 * bin.translation_share);
    }
  }
  if (e.used < e.relations && !allow_missing) {
    std::fprintf(stderr, "evaluate_relations: %d relations did not find both poses within %.6f s\n",
                 e.relations - e.used, tolerance);
    return 1;
  }
  return 0;
}
