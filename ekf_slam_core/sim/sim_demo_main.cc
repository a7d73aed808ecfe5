// ekf_slam_sim_demo: EKF-SLAM on the generated landmark world, with unknown
// association, writing what `make demo` shows (first version of the demo;
// no ROS involved).
//
//   ekf_slam_sim_demo --out DIR [--laps N] [--seed S] [--jcbb] [--max-range R]
//
// Writes into DIR: trajectory_estimated.txt, trajectory_true.txt,
// trajectory_odometry.txt (stamp x y theta), landmarks_estimated.txt
// (id x y cov_xx cov_xy cov_yy observations), landmarks_true.txt (x y),
// report.txt; prints the final pose error and the average NEES.
//
// The loop closing (the thesis's Fig. 5.2): the step in which the robot's
// position variance (the trace of its 2 × 2 block) falls the most, when a
// landmark mapped long before is seen again and, through the correlations,
// every estimate is pulled in. The filter just before and just after that
// step: landmarks_{before,after}_closing.txt (as landmarks_estimated.txt)
// and robot_{before,after}_closing.txt (stamp x y theta cov_xx cov_xy
// cov_yy).
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/sim/landmark_simulator.h"

namespace {

using ekf_slam::Pose2;

void usage() {
  std::cerr
      << "usage: ekf_slam_sim_demo --out DIR [--laps N] [--seed S] [--jcbb] [--max-range R]\n";
}

void writePose(std::ofstream& out, double stamp, const Pose2& pose) {
  out << std::fixed << std::setprecision(6) << stamp << ' ' << pose.x << ' ' << pose.y << ' '
      << pose.theta << '\n';
}

void writeLandmarks(const std::string& path, const ekf_slam::EkfSlam& filter) {
  std::ofstream lm(path);
  lm << "# id x y cov_xx cov_xy cov_yy observations\n";
  for (int slot = 0; slot < filter.landmarkCount(); ++slot) {
    const ekf_slam::Vector2 p = filter.landmarkPosition(slot);
    const ekf_slam::Matrix2 c = filter.landmarkCovariance(slot);
    lm << filter.landmarks()[slot].id << ' ' << p.x() << ' ' << p.y() << ' ' << c(0, 0) << ' '
       << c(0, 1) << ' ' << c(1, 1) << ' ' << filter.landmarks()[slot].observations << '\n';
  }
}

void writeRobot(const std::string& path, double stamp, const ekf_slam::EkfSlam& filter) {
  std::ofstream out(path);
  const Pose2 p = filter.pose();
  const ekf_slam::Matrix3 c = filter.poseCovariance();
  out << "# stamp x y theta cov_xx cov_xy cov_yy\n"
      << std::setprecision(9) << stamp << ' ' << p.x << ' ' << p.y << ' ' << p.theta << ' '
      << c(0, 0) << ' ' << c(0, 1) << ' ' << c(1, 1) << '\n';
}

double positionVariance(const ekf_slam::EkfSlam& filter) {
  const ekf_slam::Matrix3 c = filter.poseCovariance();
  return c(0, 0) + c(1, 1);
}

}  // namespace

int main(int argc, char** argv) {
  std::string out_dir;
  ekf_slam::sim::LandmarkSimOptions sim_options;
  sim_options.laps = 2;
  ekf_slam::AssociationOptions association;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--out" && i + 1 < argc) {
      out_dir = argv[++i];
    } else if (arg == "--laps" && i + 1 < argc) {
      sim_options.laps = std::atoi(argv[++i]);
    } else if (arg == "--seed" && i + 1 < argc) {
      sim_options.seed = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--max-range" && i + 1 < argc) {
      sim_options.max_range = std::atof(argv[++i]);
    } else if (arg == "--jcbb") {
      association.method = ekf_slam::AssociationMethod::kJointCompatibility;
    } else {
      usage();
      return 2;
    }
  }
  if (out_dir.empty() || sim_options.laps < 1 || !(sim_options.max_range > sim_options.min_range)) {
    usage();
    return 2;
  }
  if (::mkdir(out_dir.c_str(), 0755) != 0 && errno != EEXIST) {
    std::cerr << "ekf_slam_sim_demo: cannot create " << out_dir << ": " << std::strerror(errno)
              << "\n";
    return 1;
  }

  ekf_slam::sim::LandmarkSimulator sim(sim_options);
  ekf_slam::FilterOptions options;
  options.laser_pose = sim_options.laser_pose;
  options.motion_noise = sim_options.odometry_noise;
  ekf_slam::EkfSlam filter(options, sim.current().true_pose);

  std::ofstream est(out_dir + "/trajectory_estimated.txt");
  std::ofstream truth(out_dir + "/trajectory_true.txt");
  std::ofstream odo(out_dir + "/trajectory_odometry.txt");
  if (!est || !truth || !odo) {
    std::cerr << "ekf_slam_sim_demo: cannot write into " << out_dir << "\n";
    return 1;
  }
  // The odometry frame starts at the robot's own origin; draw it from the
  // true start so the three paths share a frame.
  const Pose2 start = sim.current().true_pose;
  const Pose2 odom_start = sim.current().odometry;
  auto odomInMap = [&](const Pose2& odom) {
    return ekf_slam::compose(start, ekf_slam::between(odom_start, odom));
  };

  Pose2 odom = sim.current().odometry;
  std::map<int, int> truth_of_id;
  auto recordNewLandmarks = [&truth_of_id](const ekf_slam::IterationReport& report,
                                           const ekf_slam::sim::SimStep& s) {
    const std::vector<int> fresh = report.association.newLandmarks();
    for (size_t i = 0; i < fresh.size() && i < report.new_landmark_ids.size(); ++i) {
      truth_of_id[report.new_landmark_ids[i]] = s.true_landmark[fresh[i]];
    }
  };
  // Map the landmarks seen from the start pose (no motion yet).
  recordNewLandmarks(
      ekf_slam::runIteration(filter, association, odom, odom, 1e-3, sim.current().observations),
      sim.current());
  double nees_sum = 0.0, nis_sum = 0.0;
  long steps = 0, nis_count = 0, failures = 0;
  long correct = 0, matches = 0;
  // The loop closing: the filter before and after the step with the
  // largest fall of the robot's position variance.
  ekf_slam::EkfSlam previous = filter, before_closing = filter, after_closing = filter;
  double largest_fall = 0.0, previous_stamp = sim.current().stamp;
  double before_stamp = previous_stamp, after_stamp = previous_stamp;
  while (sim.next()) {
    const ekf_slam::sim::SimStep& s = sim.current();
    previous = filter;
    const ekf_slam::IterationReport report = ekf_slam::runIteration(
        filter, association, odom, s.odometry, sim_options.dt, s.observations);
    if (positionVariance(previous) - positionVariance(filter) > largest_fall) {
      largest_fall = positionVariance(previous) - positionVariance(filter);
      before_closing = previous;
      after_closing = filter;
      before_stamp = previous_stamp;
      after_stamp = s.stamp;
    }
    odom = s.odometry;
    if (!report.ok()) ++failures;
    for (size_t i = 0; i < report.matches.size(); ++i) {
      ++matches;
      const auto it = truth_of_id.find(report.matches[i].landmark_id);
      if (it != truth_of_id.end() && it->second == s.true_landmark[report.matches[i].observation]) {
        ++correct;
      }
      nis_sum += report.nis[i];
      ++nis_count;
    }
    recordNewLandmarks(report, s);
    nees_sum += filter.poseNees(s.true_pose);
    ++steps;
    writePose(est, s.stamp, filter.pose());
    writePose(truth, s.stamp, s.true_pose);
    writePose(odo, s.stamp, odomInMap(s.odometry));
    previous_stamp = s.stamp;
  }

  writeLandmarks(out_dir + "/landmarks_estimated.txt", filter);
  writeLandmarks(out_dir + "/landmarks_before_closing.txt", before_closing);
  writeLandmarks(out_dir + "/landmarks_after_closing.txt", after_closing);
  writeRobot(out_dir + "/robot_before_closing.txt", before_stamp, before_closing);
  writeRobot(out_dir + "/robot_after_closing.txt", after_stamp, after_closing);
  std::ofstream lt(out_dir + "/landmarks_true.txt");
  for (const ekf_slam::Vector2& p : sim.landmarks()) lt << p.x() << ' ' << p.y() << '\n';

  const Pose2 final_truth = sim.current().true_pose;
  const Pose2 final_est = filter.pose();
  const Pose2 final_odom = odomInMap(sim.current().odometry);
  const double pos_err = std::hypot(final_est.x - final_truth.x, final_est.y - final_truth.y);
  const double yaw_err = std::abs(ekf_slam::wrapAngle(final_est.theta - final_truth.theta));
  const double odo_err = std::hypot(final_odom.x - final_truth.x, final_odom.y - final_truth.y);
  const ekf_slam::ChiSquareBand nees_band = ekf_slam::averageChiSquareBand(3, 1);
  std::ostringstream report;
  report << std::fixed << std::setprecision(4);
  report << "EKF-SLAM simulated demo (" << sim_options.laps << " laps, seed " << sim_options.seed
         << ", "
         << (association.method == ekf_slam::AssociationMethod::kNearestNeighbour
                 ? "nearest-neighbour"
                 : "JCBB")
         << " association, unknown correspondences)\n"
         << "steps: " << steps << ", rejected iterations: " << failures << "\n"
         << "final position error: " << pos_err << " m (odometry alone: " << odo_err << " m)\n"
         << "final heading error: " << ekf_slam::radToDeg(yaw_err) << " deg\n"
         << "average pose NEES: " << nees_sum / std::max(1L, steps)
         << " (expected 3; single-run 95% band per step [" << nees_band.lower << ", "
         << nees_band.upper << "])\n"
         << "average NIS: " << nis_sum / std::max(1L, nis_count) << " (expected 2)\n"
         << "landmarks: " << filter.landmarkCount() << " mapped, " << sim.landmarks().size()
         << " in the world\n"
         << "correct pairings: " << correct << " / " << matches << "\n"
         << "loop closing: at " << after_stamp << " s the robot's position variance fell from "
         << positionVariance(before_closing) << " to " << positionVariance(after_closing)
         << " m^2\n";
  std::ofstream(out_dir + "/report.txt") << report.str();
  std::cout << report.str();
  return 0;
}
