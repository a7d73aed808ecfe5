#include "ekf_slam_core/features/feature_options.h"

#include <cmath>
#include <sstream>

namespace ekf_slam {
namespace {

// Appends "FeatureOptions.<field> must be <rule>, got <value>" once.
template <typename T>
void check(bool ok, const char* field, const char* rule, T value, std::ostringstream* error) {
  if (ok || error->tellp() > 0) return;
  *error << "FeatureOptions." << field << " must be " << rule << ", got " << value;
}

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool nonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

std::string validateFeatureOptions(const FeatureOptions& o) {
  std::ostringstream e;
  check(positive(o.range_sigma), "range_sigma", "> 0 (m)", o.range_sigma, &e);
  check(nonNegative(o.bearing_sigma), "bearing_sigma", ">= 0 (rad)", o.bearing_sigma, &e);
  check(o.cluster_mode == ClusterMode::kFixed || o.cluster_mode == ClusterMode::kAdaptive,
        "cluster_mode", "kFixed or kAdaptive", static_cast<int>(o.cluster_mode), &e);
  check(positive(o.cluster_threshold), "cluster_threshold", "> 0 (m)", o.cluster_threshold, &e);
  check(std::isfinite(o.cluster_incidence_angle) && o.cluster_incidence_angle > 0.0 &&
            o.cluster_incidence_angle < kPi / 2.0,
        "cluster_incidence_angle", "in (0, pi/2) (rad)", o.cluster_incidence_angle, &e);
  check(o.cluster_max_invalid_beams >= 0, "cluster_max_invalid_beams", ">= 0 (beams)",
        o.cluster_max_invalid_beams, &e);
  check(positive(o.split_threshold), "split_threshold", "> 0 (m)", o.split_threshold, &e);
  check(positive(o.merge_chi2), "merge_chi2", "> 0", o.merge_chi2, &e);
  check(o.min_line_points >= 2, "min_line_points", ">= 2", o.min_line_points, &e);
  check(nonNegative(o.min_line_length), "min_line_length", ">= 0 (m)", o.min_line_length, &e);
  check(o.break_guard_points >= 0, "break_guard_points", ">= 0", o.break_guard_points, &e);
  check(o.end_trim_points >= 0, "end_trim_points", ">= 0", o.end_trim_points, &e);
  check(std::isfinite(o.corner_min_angle) && o.corner_min_angle > 0.0 &&
            o.corner_min_angle <= kPi / 2.0,
        "corner_min_angle", "in (0, pi/2] (rad)", o.corner_min_angle, &e);
  check(positive(o.corner_max_distance), "corner_max_distance", "> 0 (m)", o.corner_max_distance,
        &e);
  check(nonNegative(o.endpoint_max_gap), "endpoint_max_gap", ">= 0 (m)", o.endpoint_max_gap, &e);
  check(nonNegative(o.point_model_sigma), "point_model_sigma", ">= 0 (m)", o.point_model_sigma, &e);
  return e.str();
}

}  // namespace ekf_slam
