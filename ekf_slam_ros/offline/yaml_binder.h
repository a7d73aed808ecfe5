// Strict YAML → options binding: every key of a mapping must be known, every
// value is checked against its declaration, and errors name the full key path
// ("filter.motion_noise.rot_per_rot: must be >= 0 (rad²/rad²), got -1"). Keys
// absent from the YAML keep the option's default.
//
// A YamlBinder is a field visitor (ekf_slam_core/geometry/option_fields.h):
// `options.visitFields(binder)` binds a whole options struct with the bounds
// written beside its fields, the same ones its validate() checks.
#pragma once

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"

namespace ekf_slam {

class YamlBinder {
 public:
  // Every bound key's final value as text, "path.to.key" → value, in binding
  // order: what the options hold after the binding (defaults where the YAML
  // is silent). Lets a caller print or compare a whole configuration.
  using Values = std::vector<std::pair<std::string, std::string>>;

  // `errors` collects messages; shared by the children of this binder, as is
  // `values` when given.
  YamlBinder(const YAML::Node& node, const std::string& path,
             std::shared_ptr<std::vector<std::string>> errors,
             std::shared_ptr<Values> values = nullptr);

  void number(const char* key, double& value, const Bounds& bounds);
  void integer(const char* key, int& value, const Bounds& bounds);
  void integer(const char* key, long& value, const Bounds& bounds);
  void flag(const char* key, bool& value);
  void text(const char* key, std::string& value, std::initializer_list<const char*> allowed = {});
  template <class Enum>
  void choice(const char* key, Enum& value, Choices<Enum> choices) {
    std::string name;
    std::vector<std::string> names;
    for (const auto& [option, label] : choices) {
      if (option == value) name = label;
      names.emplace_back(label);
    }
    oneOf(key, &name, names);
    for (const auto& [option, label] : choices) {
      if (name == label) value = option;
    }
  }
  // A nested options struct under `key`, every key of which must be known.
  template <class Options>
  void section(const char* key, Options& options) {
    YamlBinder inner = child(key);
    options.visitFields(inner);
    inner.rejectUnknownKeys();
  }
  // A fixed-length list of numbers, e.g. a pose [x, y, theta].
  void numbers(const char* key, std::vector<double>* values, size_t count);
  // The mapping under `key` (empty binder when absent).
  YamlBinder child(const char* key);

  // Reports every key of this mapping that no call above asked for.
  void rejectUnknownKeys();

 private:
  void oneOf(const char* key, std::string* value, const std::vector<std::string>& allowed);
  std::string keyPath(const char* key) const;
  void error(const std::string& message);
  void record(const char* key, const std::string& value);

  YAML::Node node_;
  std::string path_;
  std::shared_ptr<std::vector<std::string>> errors_;
  std::shared_ptr<Values> values_;
  std::set<std::string> known_;
};

}  // namespace ekf_slam
