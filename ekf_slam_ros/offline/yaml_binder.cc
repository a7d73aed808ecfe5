#include "ekf_slam_ros/offline/yaml_binder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace ekf_slam {

namespace {

std::string exact(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", v);
  return text;
}

}  // namespace

YamlBinder::YamlBinder(const YAML::Node& node, const std::string& path,
                       std::shared_ptr<std::vector<std::string>> errors,
                       std::shared_ptr<Values> values)
    : node_(node), path_(path), errors_(std::move(errors)), values_(std::move(values)) {
  if (node_ && !node_.IsNull() && !node_.IsMap()) {
    error((path_.empty() ? std::string("document") : path_) + ": must be a mapping of keys");
    node_ = YAML::Node();
  }
}

std::string YamlBinder::keyPath(const char* key) const {
  return path_.empty() ? std::string(key) : path_ + "." + key;
}

void YamlBinder::error(const std::string& message) { errors_->push_back(message); }

void YamlBinder::record(const char* key, const std::string& value) {
  if (values_) values_->emplace_back(keyPath(key), value);
}

void YamlBinder::number(const char* key, double& value, const Bounds& bounds) {
  known_.insert(key);
  struct Record {
    YamlBinder* b;
    const char* key;
    const double* value;
    ~Record() { b->record(key, exact(*value)); }
  } recorder{this, key, &value};
  if (!node_ || !node_[key]) return;
  try {
    const double v = node_[key].as<double>();
    if (!bounds.admits(v)) {
      std::ostringstream m;
      m << keyPath(key) << ": must be " << bounds.text() << ", got " << v;
      error(m.str());
      return;
    }
    value = v;
  } catch (const YAML::Exception&) {
    error(keyPath(key) + ": must be a number");
  }
}

void YamlBinder::integer(const char* key, int& value, const Bounds& bounds) {
  long v = value;
  // Whatever the declaration says, an int holds no more than this.
  Bounds within = bounds;
  within.min = std::max(within.min, static_cast<double>(std::numeric_limits<int>::min()));
  within.max = std::min(within.max, static_cast<double>(std::numeric_limits<int>::max()));
  integer(key, v, within);
  value = static_cast<int>(v);
}

void YamlBinder::integer(const char* key, long& value, const Bounds& bounds) {
  known_.insert(key);
  struct Record {
    YamlBinder* b;
    const char* key;
    const long* value;
    ~Record() { b->record(key, std::to_string(*value)); }
  } recorder{this, key, &value};
  if (!node_ || !node_[key]) return;
  try {
    const long v = node_[key].as<long>();
    if (!bounds.admits(static_cast<double>(v))) {
      error(keyPath(key) + ": must be " + bounds.text() + ", got " + std::to_string(v));
      return;
    }
    value = v;
  } catch (const YAML::Exception&) {
    error(keyPath(key) + ": must be an integer");
  }
}

void YamlBinder::flag(const char* key, bool& value) {
  known_.insert(key);
  struct Record {
    YamlBinder* b;
    const char* key;
    const bool* value;
    ~Record() { b->record(key, *value ? "true" : "false"); }
  } recorder{this, key, &value};
  if (!node_ || !node_[key]) return;
  try {
    value = node_[key].as<bool>();
  } catch (const YAML::Exception&) {
    error(keyPath(key) + ": must be true or false");
  }
}

void YamlBinder::text(const char* key, std::string& value,
                      std::initializer_list<const char*> allowed) {
  oneOf(key, &value, std::vector<std::string>(allowed.begin(), allowed.end()));
}

void YamlBinder::oneOf(const char* key, std::string* value,
                       const std::vector<std::string>& allowed) {
  known_.insert(key);
  struct Record {
    YamlBinder* b;
    const char* key;
    const std::string* value;
    ~Record() { b->record(key, *value); }
  } recorder{this, key, value};
  if (!node_ || !node_[key]) return;
  try {
    const std::string v = node_[key].as<std::string>();
    if (!allowed.empty()) {
      bool ok = false;
      std::string list;
      for (const std::string& a : allowed) {
        ok = ok || a == v;
        list += (list.empty() ? "" : ", ") + a;
      }
      if (!ok) {
        error(keyPath(key) + ": must be one of " + list + ", got '" + v + "'");
        return;
      }
    }
    *value = v;
  } catch (const YAML::Exception&) {
    error(keyPath(key) + ": must be a string");
  }
}

void YamlBinder::numbers(const char* key, std::vector<double>* values, size_t count) {
  known_.insert(key);
  struct Record {
    YamlBinder* b;
    const char* key;
    const std::vector<double>* values;
    ~Record() {
      std::string list;
      for (double v : *values) list += (list.empty() ? "" : ", ") + exact(v);
      b->record(key, "[" + list + "]");
    }
  } recorder{this, key, values};
  if (!node_ || !node_[key]) return;
  const YAML::Node list = node_[key];
  if (!list.IsSequence() || list.size() != count) {
    error(keyPath(key) + ": must be a list of " + std::to_string(count) + " numbers");
    return;
  }
  std::vector<double> out;
  try {
    for (const YAML::Node& item : list) out.push_back(item.as<double>());
  } catch (const YAML::Exception&) {
    error(keyPath(key) + ": must be a list of " + std::to_string(count) + " numbers");
    return;
  }
  for (double v : out) {
    if (!std::isfinite(v)) {
      error(keyPath(key) + ": values must be finite");
      return;
    }
  }
  *values = out;
}

YamlBinder YamlBinder::child(const char* key) {
  known_.insert(key);
  return YamlBinder(node_ ? node_[key] : YAML::Node(), keyPath(key), errors_, values_);
}

void YamlBinder::rejectUnknownKeys() {
  if (!node_ || !node_.IsMap()) return;
  for (const auto& entry : node_) {
    const std::string key = entry.first.as<std::string>();
    if (!known_.count(key)) error(keyPath(key.c_str()) + ": unknown key");
  }
}

}  // namespace ekf_slam
