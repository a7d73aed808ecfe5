// How an options struct declares its fields: once, each with its name, its
// default (the member initializer) and, for a number, the values it admits,
// written beside the field in the struct's visitFields():
//
//   struct GateOptions {
//     double gate_probability = 0.99;  // χ²₂ quantile
//     int rounds = 2;
//
//     template <class Visitor>
//     void visitFields(Visitor& v) {
//       v.number("gate_probability", gate_probability, Bounds::open(0.0, 1.0));
//       v.integer("rounds", rounds, Bounds::atLeast(0));
//     }
//     std::string validate() const { return checkFields(*this); }
//   };
//
// validate() (through checkFields) and the configuration loaders (the YAML
// file and the ROS parameter server, ekf_slam_ros/offline/yaml_binder.h)
// walk the same visitFields(), so each range has one source and a loader
// never admits a value validate() refuses. A visitor provides:
//
//   number(name, double&, Bounds)     integer(name, int& or long&, Bounds)
//   flag(name, bool&)                 text(name, std::string&, {allowed…})
//   choice(name, Enum&, {{Enum::kA, "a"}, …})
//   section(name, Options&)           a nested struct under its own key
//
// Rules between fields (min ≤ max) stay in validate(), after checkFields.
#pragma once

#include <cmath>
#include <initializer_list>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

namespace ekf_slam {

// The values a numeric field admits: an interval whose ends are open or
// closed (infinite ends are open). Only finite values are ever admitted.
struct Bounds {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = true;
  bool max_open = true;
  const char* unit = "";  // shown after the rule: "(m)"

  static constexpr Bounds atLeast(double min, const char* unit = "") {
    return {min, std::numeric_limits<double>::infinity(), false, true, unit};
  }
  static constexpr Bounds above(double min, const char* unit = "") {
    return {min, std::numeric_limits<double>::infinity(), true, true, unit};
  }
  static constexpr Bounds closed(double min, double max, const char* unit = "") {
    return {min, max, false, false, unit};
  }
  static constexpr Bounds open(double min, double max, const char* unit = "") {
    return {min, max, true, true, unit};
  }
  static constexpr Bounds closedOpen(double min, double max, const char* unit = "") {
    return {min, max, false, true, unit};
  }
  static constexpr Bounds openClosed(double min, double max, const char* unit = "") {
    return {min, max, true, false, unit};
  }

  bool admits(double v) const {
    return std::isfinite(v) && (min_open ? v > min : v >= min) && (max_open ? v < max : v <= max);
  }

  // The rule as a person reads it: "> 0 (m)", ">= 1", "in (0, 1)".
  std::string text() const {
    std::ostringstream out;
    if (std::isinf(max)) {
      out << (min_open ? "> " : ">= ") << min;
    } else {
      out << "in " << (min_open ? '(' : '[') << min << ", " << max << (max_open ? ')' : ']');
    }
    if (*unit != '\0') out << " (" << unit << ")";
    return out.str();
  }
};

// The names an enum field takes in a configuration.
template <class Enum>
using Choices = std::initializer_list<std::pair<Enum, const char*>>;

// A visitor that checks every field against its declaration and keeps the
// first violation, named by its path ("correlative.levels must be in [1,
// 16], got 0").
class FieldChecker {
 public:
  explicit FieldChecker(std::string prefix = "") : prefix_(std::move(prefix)) {}

  void number(const char* name, double value, const Bounds& bounds) {
    if (!bounds.admits(value)) fail(name, bounds.text(), value);
  }
  template <class Integer>
  void integer(const char* name, Integer value, const Bounds& bounds) {
    if (!bounds.admits(static_cast<double>(value))) fail(name, bounds.text(), value);
  }
  void flag(const char*, bool) {}
  void text(const char* name, const std::string& value,
            std::initializer_list<const char*> allowed) {
    if (allowed.size() == 0) return;
    std::string list;
    for (const char* a : allowed) {
      if (value == a) return;
      list += (list.empty() ? "" : ", ") + std::string(a);
    }
    fail(name, "one of " + list, value);
  }
  template <class Enum>
  void choice(const char* name, Enum value, Choices<Enum> choices) {
    std::string list;
    for (const auto& [option, label] : choices) {
      if (value == option) return;
      list += (list.empty() ? "" : ", ") + std::string(label);
    }
    fail(name, "one of " + list, static_cast<long>(value));
  }
  template <class Options>
  void section(const char* name, Options& options) {
    if (!error_.empty()) return;
    FieldChecker inner(prefix_ + name + ".");
    options.visitFields(inner);
    error_ = inner.error_;
  }

  const std::string& error() const { return error_; }

 private:
  template <class Value>
  void fail(const char* name, const std::string& rule, const Value& value) {
    if (!error_.empty()) return;
    std::ostringstream out;
    out << prefix_ << name << " must be " << rule << ", got " << value;
    error_ = out.str();
  }

  std::string prefix_;
  std::string error_;
};

// The first field of `options` outside its declaration, as text; empty when
// every field is admitted. (A copy is visited: visitFields also serves the
// loaders, which write.)
template <class Options>
std::string checkFields(const Options& options) {
  Options copy = options;
  FieldChecker checker;
  copy.visitFields(checker);
  return checker.error();
}

}  // namespace ekf_slam
