#include "ekf_slam_core/features/feature_options.h"

namespace ekf_slam {

std::string validateFeatureOptions(const FeatureOptions& o) {
  const std::string error = checkFields(o);
  return error.empty() ? "" : "FeatureOptions." + error;
}

}  // namespace ekf_slam
