// The Monte Carlo NEES check of the filter's consistency tests: the
// per-step average over runs, its mean over the steps, and the fraction of
// steps whose average lies inside the chi-square band. Header only, test
// use only.
#pragma once

#include <algorithm>
#include <iostream>
#include <vector>

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {
namespace testing {

struct NeesSummary {
  size_t steps = 0;              // common to every run
  double average = 0.0;          // mean over the steps of the per-step average
  double fraction_inside = 0.0;  // of the steps whose average lies in `band`
  ChiSquareBand band;
};

// `runs` holds one NEES per step for each run (of `dof` degrees of
// freedom); steps beyond the shortest run are ignored. Prints one line.
inline NeesSummary summariseNees(const std::vector<std::vector<double>>& runs, int dof) {
  NeesSummary out;
  if (runs.empty()) return out;
  const int count = static_cast<int>(runs.size());
  out.band = averageChiSquareBand(dof, count, 0.95);
  out.steps = runs[0].size();
  for (const auto& run : runs) out.steps = std::min(out.steps, run.size());
  if (out.steps == 0) return out;
  double total = 0.0;
  int inside = 0;
  for (size_t k = 0; k < out.steps; ++k) {
    double sum = 0.0;
    for (const auto& run : runs) sum += run[k];
    const double average = sum / count;
    total += average;
    if (average >= out.band.lower && average <= out.band.upper) ++inside;
  }
  out.average = total / out.steps;
  out.fraction_inside = static_cast<double>(inside) / out.steps;
  std::cout << "average NEES over " << count << " runs x " << out.steps << " steps: " << out.average
            << " (95% band for a " << count << "-run average: [" << out.band.lower << ", "
            << out.band.upper << "]); steps inside the band: " << 100.0 * out.fraction_inside
            << "%\n";
  return out;
}

}  // namespace testing
}  // namespace ekf_slam
