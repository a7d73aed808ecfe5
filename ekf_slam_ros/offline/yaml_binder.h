// Strict YAML → options binding: every key of a mapping must be known, every
// value is range-checked, and errors name the full key path
// ("filter.motion_noise.rot_per_rot: must be >= 0, got -1"). Keys absent
// from the YAML keep the option's default.
#pragma once

#include <yaml-cpp/yaml.h>

#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

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

  void number(const char* key, double* value, double min, double max);
  void integer(const char* key, int* value, int min, int max);
  void integer(const char* key, long* value, long min, long max);
  void boolean(const char* key, bool* value);
  void text(const char* key, std::string* value, const std::vector<std::string>& allowed = {});
  // A fixed-length list of numbers, e.g. a pose [x, y, theta].
  void numbers(const char* key, std::vector<double>* values, size_t count);
  // The mapping under `key` (empty binder when absent).
  YamlBinder child(const char* key);

  // Reports every key of this mapping that no call above asked for.
  void rejectUnknownKeys();

 private:
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
