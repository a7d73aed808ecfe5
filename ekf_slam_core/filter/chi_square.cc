#include "ekf_slam_core/filter/chi_square.h"

#include <boost/math/distributions/chi_squared.hpp>

namespace ekf_slam {

double chiSquareQuantile(double probability, double dof) {
  return boost::math::quantile(boost::math::chi_squared(dof), probability);
}

ChiSquareBand averageChiSquareBand(double dof, int samples, double confidence) {
  // The sum of n independent χ²_dof is χ²_{n·dof}; divide its band by n.
  const double tail = (1.0 - confidence) / 2.0;
  const double n = samples;
  return {chiSquareQuantile(tail, n * dof) / n, chiSquareQuantile(1.0 - tail, n * dof) / n};
}

}  // namespace ekf_slam
