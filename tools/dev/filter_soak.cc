// ekf_slam_filter_soak: a long run of the EKF on the landmark simulator
// (the default 10 m × 6 m loop, unknown association), to show that memory
// stays flat once the map is built and that the covariance stays symmetric
// and positive semi-definite over millions of iterations.
//
//   ekf_slam_filter_soak [--iterations N] [--every K] [--seed S]
//                        [--first-estimate-jacobians] --out FILE
//
// Every K iterations (default 1000) it writes one line to FILE:
//   iteration rss_kib landmarks min_eigenvalue pose_error_m
// with the smallest eigenvalue of the full covariance and the distance to
// the true pose. The filter stores one triangle of P, so P is symmetric by
// construction; what can fail is positive semi-definiteness (an update that
// loses it shows as a negative eigenvalue). Every iteration checks that the
// pose covariance's diagonal is positive and finite. Prints a summary;
// exits 1 when a check failed.
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>

#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/sim/landmark_simulator.h"

namespace {

long residentKib() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

void usage() {
  std::cerr << "usage: ekf_slam_filter_soak [--iterations N] [--every K] [--seed S] "
               "[--first-estimate-jacobians]\n"
               "                            --out FILE\n";
}

}  // namespace

int main(int argc, char** argv) {
  long iterations = 1000000, every = 1000;
  bool first_estimates = false;
  std::string out_path;
  ekf_slam::sim::LandmarkSimOptions sim_options;
  sim_options.laps = std::numeric_limits<int>::max();
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--iterations" && i + 1 < argc) {
      iterations = std::atol(argv[++i]);
    } else if (arg == "--every" && i + 1 < argc) {
      every = std::atol(argv[++i]);
    } else if (arg == "--seed" && i + 1 < argc) {
      sim_options.seed = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--first-estimate-jacobians") {
      first_estimates = true;
    } else if (arg == "--out" && i + 1 < argc) {
      out_path = argv[++i];
    } else {
      usage();
      return 2;
    }
  }
  if (out_path.empty() || iterations < 1 || every < 1) {
    usage();
    return 2;
  }
  std::ofstream out(out_path);
  if (!out) {
    std::cerr << "ekf_slam_filter_soak: cannot write " << out_path << "\n";
    return 2;
  }
  out << "# iteration rss_kib landmarks min_eigenvalue pose_error_m\n";

  ekf_slam::sim::LandmarkSimulator sim(sim_options);
  ekf_slam::FilterOptions options;
  options.laser_pose = sim_options.laser_pose;
  options.motion_noise = sim_options.odometry_noise;
  options.first_estimate_jacobians = first_estimates;
  ekf_slam::EkfSlam filter(options, sim.current().true_pose);
  const ekf_slam::AssociationOptions association;
  ekf_slam::Pose2 odom = sim.current().odometry;
  ekf_slam::runIteration(filter, association, odom, odom, 1e-3, sim.current().observations);

  long failures = 0, bad_checks = 0;
  long warm_rss = 0, max_rss_after_warmup = 0;
  double lowest_eigenvalue = std::numeric_limits<double>::infinity();
  const long warmup = iterations / 10;
  for (long k = 1; k <= iterations; ++k) {
    if (!sim.next()) break;
    const ekf_slam::sim::SimStep& s = sim.current();
    const ekf_slam::IterationReport report = ekf_slam::runIteration(
        filter, association, odom, s.odometry, sim_options.dt, s.observations);
    odom = s.odometry;
    if (!report.ok()) ++failures;
    const ekf_slam::Matrix3 pose_cov = filter.poseCovariance();
    if (!pose_cov.allFinite() || !(pose_cov.diagonal().array() > 0.0).all()) ++bad_checks;
    if (k % every != 0) continue;
    const Eigen::MatrixXd P = filter.covariance();
    const double min_eigenvalue =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P, Eigen::EigenvaluesOnly)
            .eigenvalues()
            .minCoeff();
    // PSD up to rounding: relative to the largest variance.
    if (!(min_eigenvalue > -1e-9 * P.diagonal().maxCoeff())) ++bad_checks;
    const long rss = residentKib();
    if (k == warmup || (warm_rss == 0 && k > warmup)) warm_rss = rss;
    if (k > warmup) max_rss_after_warmup = std::max(max_rss_after_warmup, rss);
    lowest_eigenvalue = std::min(lowest_eigenvalue, min_eigenvalue);
    const ekf_slam::Pose2 pose = filter.pose();
    const double error = std::hypot(pose.x - s.true_pose.x, pose.y - s.true_pose.y);
    out << k << ' ' << rss << ' ' << filter.landmarkCount() << ' ' << min_eigenvalue << ' ' << error
        << '\n';
  }
  out.flush();
  std::printf(
      "filter soak: %ld iterations, %d landmarks, %ld refused updates, %ld failed checks\n"
      "RSS %ld KiB after warm-up (iteration %ld), at most %ld KiB after it (+%ld KiB)\n"
      "covariance: lowest eigenvalue %.3g\n",
      filter.step(), filter.landmarkCount(), failures, bad_checks, warm_rss, warmup,
      max_rss_after_warmup, max_rss_after_warmup - warm_rss, lowest_eigenvalue);
  return bad_checks == 0 ? 0 : 1;
}
