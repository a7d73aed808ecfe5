#include "ekf_slam_core/features/line_fit.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {

Vector2 LineFit::normal() const { return Vector2(std::cos(theta), std::sin(theta)); }
Vector2 LineFit::direction() const { return Vector2(-std::sin(theta), std::cos(theta)); }
Vector2 LineFit::project(const Vector2& point) const {
  const Vector2 n = normal();
  return point - (n.dot(point) - p) * n;
}

namespace {

// The fit; the covariance loop runs only when `with_covariance`.
bool fit(const std::vector<ScanPoint>& points, int first, int last, double range_sigma,
         double bearing_sigma, bool with_covariance, LineFit* out,
         std::vector<Matrix2>* J_per_point) {
  const int n = last - first + 1;
  if (n < 2 || first < 0 || last >= static_cast<int>(points.size())) return false;
  Vector2 centroid = Vector2::Zero();
  for (int i = first; i <= last; ++i) centroid += points[i].xy;
  centroid /= n;
  const double var_r = range_sigma * range_sigma;
  const double var_phi = bearing_sigma * bearing_sigma;
  const bool with_noise_model = var_r > 0.0 || var_phi > 0.0;
  // Bias correction. Each reading's Cartesian noise is anisotropic:
  // C_i = σ_r² u_i u_iᵀ + σ_φ² r_i² v_i v_iᵀ (u_i along the beam, v_i across
  // it), so the scatter of the readings about their centroid is in
  // expectation the true scatter plus K = (1 − 1/n) Σ C_i. Plain total least
  // squares takes the eigenvector of the raw scatter and tilts a line seen
  // obliquely by about K_nt / Σt²: a bias that does not shrink with more
  // readings and reached 0.3σ on 0.35 m carton faces. Removing K first (the
  // adjusted least-squares estimator) makes the fit consistent.
  // Scatter S of the readings about the centroid, and Σ C_i.
  double sxx = 0.0, syy = 0.0, sxy = 0.0;
  double kxx = 0.0, kyy = 0.0, kxy = 0.0;
  for (int i = first; i <= last; ++i) {
    const Vector2 q = points[i].xy - centroid;
    sxx += q.x() * q.x();
    syy += q.y() * q.y();
    sxy += q.x() * q.y();
    if (with_noise_model) {
      const Vector2& u = points[i].direction;
      const double across = var_phi * points[i].range * points[i].range;
      kxx += var_r * u.x() * u.x() + across * u.y() * u.y();
      kyy += var_r * u.y() * u.y() + across * u.x() * u.x();
      kxy += (var_r - across) * u.x() * u.y();
    }
  }
  const double spread = sxx + syy;
  if (!(spread > 1e-20 * n * (1.0 + centroid.squaredNorm()))) return false;

  const double shrink = with_noise_model ? 1.0 - 1.0 / n : 0.0;
  kxx *= shrink;
  kyy *= shrink;
  kxy *= shrink;
  // Sum of squared distances along θ of the corrected scatter:
  // ½(Cxx+Cyy) + ½(Cxx−Cyy)cos2θ + Cxy sin2θ, smallest for
  // 2θ = atan2(−2Cxy, Cyy − Cxx). Without a dominant direction there is no
  // unique line. Should the correction swamp the data (a handful of readings
  // within a few σ of each other), the raw scatter is used.
  double cxx = sxx - kxx, cyy = syy - kyy, cxy = sxy - kxy;
  bool corrected = with_noise_model;
  double anisotropy = std::hypot(cyy - cxx, 2.0 * cxy);
  if (corrected && !(anisotropy > 0.5 * std::hypot(syy - sxx, 2.0 * sxy))) {
    cxx = sxx;
    cyy = syy;
    cxy = sxy;
    corrected = false;
    anisotropy = std::hypot(cyy - cxx, 2.0 * cxy);
  }
  if (!(anisotropy > 1e-12 * spread)) return false;
  double theta = 0.5 * std::atan2(-2.0 * cxy, cyy - cxx);
  // cos θ, sin θ from cos 2θ (half-angle; θ in [−π/2, π/2] so cos θ >= 0).
  const double cos_2theta = (cyy - cxx) / anisotropy;
  const double c = std::sqrt(std::max(0.0, 0.5 * (1.0 + cos_2theta)));
  const double s = std::copysign(std::sqrt(std::max(0.0, 0.5 * (1.0 - cos_2theta))), theta);
  double p = centroid.x() * c + centroid.y() * s;

  // Residuals d_i (along the normal) and along-line coordinates t_i, both
  // relative to the centroid. The estimating equation is
  // F(θ) = nᵀ(S − K)t = Σ d_i t_i − nᵀK t = 0; D = ∂F/∂θ = tᵀ(S−K)t − nᵀ(S−K)n
  // (= the corrected anisotropy) > 0.
  const double sum_d2 = c * c * sxx + 2.0 * c * s * sxy + s * s * syy;  // raw, for residuals
  const double D = anisotropy;
  const double sign = p < 0.0 ? -1.0 : 1.0;  // flip to p >= 0: θ += π, ∂p changes sign
  const double lever = -centroid.x() * s + centroid.y() * c;  // ∂p/∂θ at fixed centroid
  Matrix2 covariance = Matrix2::Zero();
  if (J_per_point) J_per_point->resize(n);
  double max_d = 0.0;
  for (int i = first; i <= last; ++i) {
    const ScanPoint& pt = points[i];
    const Vector2 q = pt.xy - centroid;
    const double d = q.x() * c + q.y() * s;
    max_d = std::max(max_d, std::abs(d));
    if (!with_covariance) continue;
    const double t = -q.x() * s + q.y() * c;
    // ∂(p, θ)/∂(x_i, y_i)
    Matrix2 J_line_xy;
    const double dtheta_dx = -(c * t - s * d) / D;
    const double dtheta_dy = -(s * t + c * d) / D;
    J_line_xy << sign * (c / n + lever * dtheta_dx), sign * (s / n + lever * dtheta_dy), dtheta_dx,
        dtheta_dy;
    // ∂(x_i, y_i)/∂(r_i, φ_i)
    const double cb = pt.direction.x(), sb = pt.direction.y();
    Matrix2 J_xy_polar;
    J_xy_polar << cb, -pt.range * sb, sb, pt.range * cb;
    Matrix2 J = J_line_xy * J_xy_polar;
    if (corrected) {
      // K depends on the reading too: nᵀC_i t = ½(σ_r² − σ_φ² r²) sin 2α with
      // α = φ − θ, and ∂θ = +∂(nᵀKt)/D.
      const double sin_a = sb * c - cb * s, cos_a = cb * c + sb * s;
      const double sin_2a = 2.0 * sin_a * cos_a, cos_2a = cos_a * cos_a - sin_a * sin_a;
      const double dtheta_dr = -shrink * var_phi * pt.range * sin_2a / D;
      const double dtheta_dphi = shrink * (var_r - var_phi * pt.range * pt.range) * cos_2a / D;
      J(1, 0) += dtheta_dr;
      J(1, 1) += dtheta_dphi;
      J(0, 0) += sign * lever * dtheta_dr;
      J(0, 1) += sign * lever * dtheta_dphi;
    }
    covariance +=
        var_r * J.col(0) * J.col(0).transpose() + var_phi * J.col(1) * J.col(1).transpose();
    if (J_per_point) (*J_per_point)[i - first] = J;
  }
  if (sign < 0.0) {
    p = -p;
    theta += kPi;
  }
  out->p = p;
  out->theta = wrapAngle(theta);
  out->covariance = covariance;
  out->centroid = centroid;
  out->rms_residual = std::sqrt(std::max(0.0, sum_d2) / n);
  out->max_residual = max_d;
  out->num_points = n;
  return true;
}

}  // namespace

bool fitLine(const std::vector<ScanPoint>& points, int first, int last, double range_sigma,
             double bearing_sigma, LineFit* out, std::vector<Matrix2>* J_per_point) {
  return fit(points, first, last, range_sigma, bearing_sigma, true, out, J_per_point);
}

bool fitLineGeometry(const std::vector<ScanPoint>& points, int first, int last, LineFit* out) {
  return fit(points, first, last, 0.0, 0.0, false, out, nullptr);
}

bool intersectLines(double p1, double theta1, double p2, double theta2, Vector2* point,
                    Matrix2* J_out_line1, Matrix2* J_out_line2) {
  const double c1 = std::cos(theta1), s1 = std::sin(theta1);
  const double c2 = std::cos(theta2), s2 = std::sin(theta2);
  const double det = c1 * s2 - s1 * c2;  // sin(θ2 − θ1)
  if (!(std::abs(det) >= 1e-6)) return false;
  // A x = (p1, p2) with rows (cos θk, sin θk).
  Matrix2 A_inv;
  A_inv << s2, -s1, -c2, c1;
  A_inv /= det;
  const Vector2 x = A_inv * Vector2(p1, p2);
  // Row k: ∂/∂θk gives (−sθk x + cθk y) + A_k ∂x/∂θk = 0.
  if (J_out_line1) {
    J_out_line1->col(0) = A_inv.col(0);
    J_out_line1->col(1) = A_inv.col(0) * (s1 * x.x() - c1 * x.y());
  }
  if (J_out_line2) {
    J_out_line2->col(0) = A_inv.col(1);
    J_out_line2->col(1) = A_inv.col(1) * (s2 * x.x() - c2 * x.y());
  }
  *point = x;
  return true;
}

bool pointToRangeBearing(const Vector2& point, Vector2* range_bearing, Matrix2* J_out_point) {
  const double r2 = point.squaredNorm();
  if (!(r2 > 0.0)) return false;
  const double r = std::sqrt(r2);
  if (J_out_point) {
    *J_out_point << point.x() / r, point.y() / r, -point.y() / r2, point.x() / r2;
  }
  *range_bearing = Vector2(r, std::atan2(point.y(), point.x()));
  return true;
}

}  // namespace ekf_slam
