// The one-dimensional Kalman localisation of thesis §3.3.1, kept as a
// worked example of how the gain trades prediction against observation.
//
// A robot on a line: x_{k+1} = x_k + u_k + v_k,  v ~ N(0, Q)
// observes its own position: z_k = x_k + w_k,    w ~ N(0, R)
//   predict:  x⁻ = x + u,       P⁻ = P + Q
//   gain:     K = P⁻ / (P⁻ + R) = 1 / (1 + R/P⁻)      (0 < K < 1)
//   update:   x = x⁻ + K (z − x⁻),  P = (1 − K) P⁻
// Conclusions reproduced in scalar_kalman_test.cc: K → 1 (trust z) when
// R ≪ P⁻, K → 0 (keep the prior) when R ≫ P⁻, the variance never depends
// on the value observed, and observations stop the growth of P.
#pragma once

namespace ekf_slam {

class ScalarKalman {
 public:
  ScalarKalman(double x, double variance) : x_(x), p_(variance) {}

  void predict(double u, double motion_variance) {
    x_ += u;
    p_ += motion_variance;
  }

  // Returns the gain used.
  double update(double z, double measurement_variance) {
    const double gain = p_ / (p_ + measurement_variance);
    x_ += gain * (z - x_);
    p_ *= (1.0 - gain);
    return gain;
  }

  double mean() const { return x_; }
  double variance() const { return p_; }

 private:
  double x_;
  double p_;
};

}  // namespace ekf_slam
