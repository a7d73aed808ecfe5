// Serves the field visitors of ekf_slam_core/geometry/option_fields.h from
// a node's private parameters: a parameter struct declares each field once
// in its visitFields() (name, default as the member initializer, bounds and
// unit), and `params.visitFields(fields)` reads them all through
// PrivateParams, with its checks and messages ("<resolved key>: must be in
// [a, b], got c"; wrong types named; unknown keys rejected by
// PrivateParams::rejectUnknown). The same visitFields() serves the YAML
// binder (ekf_slam_ros/offline/yaml_binder.h) and checkFields().
#pragma once

#include <initializer_list>
#include <string>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ros_params/private_params.h"

namespace ekf_slam {

class PrivateParamFields {
 public:
  explicit PrivateParamFields(PrivateParams& read) : read_(read) {}

  void number(const char* key, double& value, const Bounds& bounds);
  void integer(const char* key, int& value, const Bounds& bounds);
  void flag(const char* key, bool& value) { read_.flag(key, &value); }
  // Non-empty `allowed`: the value must be one of them ("must be 'a' or
  // 'b', not 'c'"). Whether a text may be empty is the struct's own rule.
  void text(const char* key, std::string& value, std::initializer_list<const char*> allowed = {});

 private:
  PrivateParams& read_;
};

}  // namespace ekf_slam
