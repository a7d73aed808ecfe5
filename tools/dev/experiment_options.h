// The command line the simulation experiments share (line_experiment.cc,
// rooms_experiment.cc): where to write, how many Monte Carlo runs, the
// first seed, and a factor on the odometry noise's standard deviations.
#pragma once

#include <cstdlib>
#include <iostream>
#include <string>

#include "ekf_slam_core/models/odometry_motion_model.h"

namespace ekf_slam {

struct ExperimentOptions {
  std::string out_dir;
  int runs = 30;
  unsigned first_seed = 1;
  double noise_scale = 1.0;
};

// Parses --out DIR [--runs N] [--seed S] [--odometry-noise-scale F] over
// the defaults in `options`. False (after printing the usage of `program`)
// on an unknown or incomplete argument, or values that cannot run.
inline bool parseExperimentOptions(int argc, char** argv, const std::string& program,
                                   ExperimentOptions* options) {
  bool ok = true;
  for (int i = 1; i < argc && ok; ++i) {
    const std::string arg = argv[i];
    if (arg == "--out" && i + 1 < argc) {
      options->out_dir = argv[++i];
    } else if (arg == "--runs" && i + 1 < argc) {
      options->runs = std::atoi(argv[++i]);
    } else if (arg == "--seed" && i + 1 < argc) {
      options->first_seed = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--odometry-noise-scale" && i + 1 < argc) {
      options->noise_scale = std::atof(argv[++i]);
    } else {
      ok = false;
    }
  }
  ok = ok && !options->out_dir.empty() && options->runs >= 1 && options->noise_scale > 0.0;
  if (!ok) {
    std::cerr << "usage: " << program
              << " --out DIR [--runs N] [--seed S] [--odometry-noise-scale F]\n";
  }
  return ok;
}

// The odometry noise's standard deviations times `scale` (the quadratic
// terms' variances times scale²): --odometry-noise-scale.
inline void scaleOdometryNoise(double scale, MotionNoiseOptions* noise) {
  for (double* variance : {&noise->rot_per_rot, &noise->rot_per_trans, &noise->trans_per_trans,
                           &noise->trans_per_rot}) {
    *variance *= scale * scale;
  }
}

}  // namespace ekf_slam
