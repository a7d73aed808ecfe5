#include "ros_params/param_fields.h"

#include <limits>
#include <sstream>

namespace ekf_slam {
namespace {

// A bound as PrivateParams takes it: an infinite end becomes the largest
// finite number, which every finite value passes.
double finite(double bound) {
  const double largest = std::numeric_limits<double>::max();
  return bound > largest ? largest : (bound < -largest ? -largest : bound);
}

}  // namespace

void PrivateParamFields::number(const char* key, double& value, const Bounds& bounds) {
  double read = value;
  read_.number(key, &read, finite(bounds.min), finite(bounds.max));
  // An open end (none among the nodes' parameters so far) is checked here,
  // named by its rule.
  if (!bounds.admits(read)) {
    std::ostringstream text;
    text << "must be " << bounds.text() << ", got " << read;
    read_.fail(key, text.str());
    return;
  }
  value = read;
}

void PrivateParamFields::integer(const char* key, int& value, const Bounds& bounds) {
  const int largest = std::numeric_limits<int>::max();
  const int low = bounds.min < -largest ? -largest : static_cast<int>(bounds.min);
  const int high = bounds.max > largest ? largest : static_cast<int>(bounds.max);
  read_.integer(key, &value, low, high);
}

void PrivateParamFields::text(const char* key, std::string& value,
                              std::initializer_list<const char*> allowed) {
  read_.text(key, &value, /*required=*/false);
  if (allowed.size() == 0) return;
  std::string list;
  size_t i = 0;
  for (const char* a : allowed) {
    if (value == a) return;
    list +=
        (i == 0 ? "" : (i + 1 == allowed.size() ? " or " : ", ")) + ("'" + std::string(a) + "'");
    ++i;
  }
  read_.fail(key, "must be " + list + ", not '" + value + "'");
}

}  // namespace ekf_slam
