#include "ros_params/private_params.h"

#include <cmath>
#include <sstream>

namespace ekf_slam {

void PrivateParams::number(const std::string& key, double* value, double low, double high) {
  known_.insert(key);
  if (!node_.hasParam(key)) return;
  double read = *value;
  if (!node_.getParam(key, read)) {
    int whole = 0;  // "robot_radius: 1" arrives as an int
    if (!node_.getParam(key, whole)) return fail(key, "must be a number");
    read = whole;
  }
  if (!std::isfinite(read) || read < low || read > high) {
    std::ostringstream text;
    text << "must be in [" << low << ", " << high << "], got " << read;
    return fail(key, text.str());
  }
  *value = read;
}

void PrivateParams::integer(const std::string& key, int* value, int low, int high) {
  known_.insert(key);
  if (!node_.hasParam(key)) return;
  // Read as XmlRpc to see the type: getParam(key, int&) rounds a double
  // (2.5 would silently become 2).
  XmlRpc::XmlRpcValue raw;
  if (!node_.getParam(key, raw)) return fail(key, "must be an integer");
  if (raw.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
    std::ostringstream text;
    text << "must be an integer, got " << static_cast<double>(raw);
    return fail(key, text.str());
  }
  if (raw.getType() != XmlRpc::XmlRpcValue::TypeInt) return fail(key, "must be an integer");
  const int read = static_cast<int>(raw);
  if (read < low || read > high) {
    return fail(key, "must be in [" + std::to_string(low) + ", " + std::to_string(high) +
                         "], got " + std::to_string(read));
  }
  *value = read;
}

void PrivateParams::flag(const std::string& key, bool* value) {
  known_.insert(key);
  if (!node_.hasParam(key)) return;
  if (!node_.getParam(key, *value)) fail(key, "must be true or false");
}

void PrivateParams::text(const std::string& key, std::string* value, bool required) {
  known_.insert(key);
  if (node_.hasParam(key) && !node_.getParam(key, *value)) return fail(key, "must be a string");
  if (required && value->empty()) fail(key, "is required and must not be empty");
}

void PrivateParams::fail(const std::string& key, const std::string& why) {
  errors_.push_back(node_.resolveName(key) + ": " + why);
}

void PrivateParams::rejectUnknown() {
  std::vector<std::string> names;
  node_.getParamNames(names);
  const std::string prefix = node_.getNamespace() + "/";
  std::set<std::string> reported;  // a nested unknown key is reported once
  for (const std::string& name : names) {
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string key = name.substr(prefix.size());
    const std::string top = key.substr(0, key.find('/'));
    if (!known_.count(top) && reported.insert(top).second) {
      fail(top, "is not a parameter of this node (typo?)");
    }
  }
}

std::string PrivateParams::errors() const {
  std::string all;
  for (const std::string& error : errors_) all += (all.empty() ? "" : "\n") + error;
  return all;
}

}  // namespace ekf_slam
