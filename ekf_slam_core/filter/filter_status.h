// Outcome of a filter operation. Anything but kOk leaves the state unchanged;
// callers count and report these (diagnostics), nothing throws.
#pragma once

namespace ekf_slam {

enum class FilterStatus {
  kOk,
  kNonFiniteInput,        // NaN or infinite odometry, observation or covariance
  kBadTimeStep,           // dt not finite or not > 0
  kOdometryJump,          // odometry increment beyond FilterOptions bounds
  kSingularInnovation,    // innovation covariance not positive definite
  kUnknownLandmark,       // an association names a landmark not in the state
  kBadObservation,        // e.g. a landmark at the sensor origin
  kMappingDisabled,       // augment refused: the filter localises only (setMappingEnabled)
  kDuplicateLandmark,     // add*Landmark with an id already in the map
  kUnrepresentablePrior,  // add*Landmark: variance beyond kMaxPriorVariance, or nearly singular
};

const char* toString(FilterStatus status);

}  // namespace ekf_slam
