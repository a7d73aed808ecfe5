#include "ekf_slam_core/smoother/rts_smoother.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// A linear-Gaussian chain x_{k+1} = A x_k + w_k, z_k = x_k + v_k, small
// angles so that wrapping never acts. The RTS smoother must reproduce the
// batch solution of the whole joint Gaussian exactly.
struct LinearChain {
  Matrix3 A, Q, R, P0;
  Vector3 m0;
  std::vector<Vector3> z;
};

LinearChain makeChain(int steps, unsigned seed) {
  LinearChain c;
  c.A << 1.0, 0.1, 0.0, 0.0, 1.0, 0.05, 0.0, 0.0, 0.98;
  c.Q = Vector3(0.01, 0.02, 0.001).asDiagonal();
  c.R = Vector3(0.05, 0.05, 0.002).asDiagonal();
  c.P0 = Vector3(0.1, 0.1, 0.01).asDiagonal();
  c.m0 = Vector3(0.2, -0.1, 0.05);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Vector3 x = c.m0;
  for (int k = 0; k < steps; ++k) {
    if (k > 0) {
      x = c.A * x + c.Q.diagonal().cwiseSqrt().cwiseProduct(Vector3(n(rng), n(rng), n(rng)));
    }
    c.z.push_back(x + c.R.diagonal().cwiseSqrt().cwiseProduct(Vector3(n(rng), n(rng), n(rng))));
  }
  return c;
}

// Forward Kalman filter over the chain, observing every `observe_every`-th
// step, recording what the EKF-SLAM run records.
TrajectoryRecorder runForward(const LinearChain& c, int steps, int observe_every) {
  TrajectoryRecorder recorder;
  Vector3 x = c.m0;
  Matrix3 P = c.P0;
  for (int k = 0; k < steps; ++k) {
    if (k > 0) {
      x = c.A * x;
      P = c.A * P * c.A.transpose() + c.Q;
      recorder.addTransition(c.A, Pose2::fromVector(x), P);
    }
    if (k % observe_every == 0) {
      const Matrix3 K = P * (P + c.R).inverse();
      x = x + K * (c.z[k] - x);
      P = (Matrix3::Identity() - K) * P;
      P = 0.5 * (P + P.transpose()).eval();
    }
    recorder.addFiltered(k, Pose2::fromVector(x), P);
  }
  return recorder;
}

TEST(RtsSmoother, ReproducesTheBatchSolutionOfALinearGaussianChain) {
  const int N = 40;
  const LinearChain c = makeChain(N, 11);

  const TrajectoryRecorder recorder = runForward(c, N, 1);
  const std::vector<SmoothedPose> smoothed = smoothTrajectory(recorder.steps());

  // Batch: information matrix Λ and vector η of all 3N states.
  MatrixXd L = MatrixXd::Zero(3 * N, 3 * N);
  VectorXd eta = VectorXd::Zero(3 * N);
  const Matrix3 P0i = c.P0.inverse(), Qi = c.Q.inverse(), Ri = c.R.inverse();
  L.block<3, 3>(0, 0) += P0i;
  eta.segment<3>(0) += P0i * c.m0;
  for (int k = 0; k < N; ++k) {
    L.block<3, 3>(3 * k, 3 * k) += Ri;
    eta.segment<3>(3 * k) += Ri * c.z[k];
    if (k + 1 < N) {
      // (x_{k+1} − A x_k)ᵀ Q⁻¹ (x_{k+1} − A x_k)
      L.block<3, 3>(3 * k, 3 * k) += c.A.transpose() * Qi * c.A;
      L.block<3, 3>(3 * k, 3 * k + 3) -= c.A.transpose() * Qi;
      L.block<3, 3>(3 * k + 3, 3 * k) -= Qi * c.A;
      L.block<3, 3>(3 * k + 3, 3 * k + 3) += Qi;
    }
  }
  const VectorXd mean = L.ldlt().solve(eta);
  const MatrixXd cov = L.inverse();
  ASSERT_EQ(smoothed.size(), static_cast<size_t>(N));
  for (int k = 0; k < N; ++k) {
    EXPECT_LT((smoothed[k].pose.vector() - mean.segment<3>(3 * k)).cwiseAbs().maxCoeff(), 1e-9)
        << "step " << k;
    EXPECT_LT((smoothed[k].covariance - cov.block<3, 3>(3 * k, 3 * k)).cwiseAbs().maxCoeff(), 1e-9)
        << "step " << k;
  }
}

TEST(RtsSmoother, SmoothedCovarianceIsNeverLargerThanFiltered) {
  const int N = 60;
  const LinearChain c = makeChain(N, 3);
  const TrajectoryRecorder recorder = runForward(c, N, 5);  // observations only now and then
  const std::vector<SmoothedPose> smoothed = smoothTrajectory(recorder.steps());
  for (int k = 0; k < N; ++k) {
    const Matrix3 difference = recorder.steps()[k].filtered_cov - smoothed[k].covariance;
    const double min_eig =
        Eigen::SelfAdjointEigenSolver<Matrix3>(difference).eigenvalues().minCoeff();
    EXPECT_GE(min_eig, -1e-12) << "step " << k;
    const double filtered_trace = recorder.steps()[k].filtered_cov.trace();
    if (k < 55) {
      // An observation follows (the last is at k = 55): strictly better.
      EXPECT_LT(smoothed[k].covariance.trace(), filtered_trace - 1e-6) << "step " << k;
    } else {
      // Nothing is observed after: the smoother cannot add information.
      EXPECT_NEAR(smoothed[k].covariance.trace(), filtered_trace, 1e-12) << "step " << k;
    }
  }
  // The last step has nothing after it: smoothed = filtered.
  EXPECT_EQ(smoothed.back().covariance, recorder.steps().back().filtered_cov);
}

TEST(RtsSmoother, AngleCorrectionsAreWrapped) {
  // Two steps whose headings straddle ±π: the correction must be small.
  TrajectoryRecorder recorder;
  const Matrix3 P = Matrix3::Identity() * 0.01;
  recorder.addFiltered(0.0, Pose2(0, 0, kPi - 0.01), P);
  recorder.addTransition(Matrix3::Identity(), Pose2(0, 0, kPi - 0.01), P * 2);
  recorder.addFiltered(1.0, Pose2(0, 0, -kPi + 0.01), P);
  const std::vector<SmoothedPose> s = smoothTrajectory(recorder.steps());
  EXPECT_LT(std::abs(wrapAngle(s[0].pose.theta - kPi)), 0.02);
}

TEST(RtsSmoother, EmptyAndSingleStep) {
  EXPECT_TRUE(smoothTrajectory({}).empty());
  TrajectoryRecorder recorder;
  recorder.addTransition(Matrix3::Identity(), Pose2(), Matrix3::Identity());  // ignored
  recorder.addFiltered(2.0, Pose2(1, 2, 0.3), Matrix3::Identity());
  const auto s = smoothTrajectory(recorder.steps());
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].pose.x, 1.0);
}

}  // namespace
}  // namespace ekf_slam
