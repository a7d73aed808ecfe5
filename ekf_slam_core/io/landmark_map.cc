#include "ekf_slam_core/io/landmark_map.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "ekf_slam_core/io/atomic_file.h"
#include "ekf_slam_core/io/yaml_fields.h"

namespace ekf_slam {
namespace {

using io_yaml::describe;
using io_yaml::lineOf;
using io_yaml::scalarNumber;

// A problem with the file and the 1-based line it is on (0: the file as a
// whole); an empty `text` is none.
struct Problem {
  int line = 0;
  std::string text;
  bool none() const { return text.empty(); }
};

Problem at(const YAML::Node& node, const std::string& text) { return {lineOf(node), text}; }

using Fields = std::map<std::string, YAML::Node>;

// The keys of one entry, each once and known, the required ones present.
Problem readFields(const YAML::Node& entry, std::initializer_list<const char*> known,
                   std::initializer_list<const char*> required, Fields* fields) {
  if (!entry.IsMap()) return at(entry, "expected an entry {id: .., ...}, got " + describe(entry));
  for (const auto& pair : entry) {
    if (!pair.first.IsScalar())
      return at(pair.first, "expected a key, got " + describe(pair.first));
    const std::string& key = pair.first.Scalar();
    if (fields->count(key)) return at(pair.first, "key '" + key + "' given twice");
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      return at(pair.first, "unknown key '" + key + "'");
    }
    (*fields)[key] = pair.second;
  }
  for (const char* key : required) {
    if (!fields->count(key)) return at(entry, std::string("missing key '") + key + "'");
  }
  return {};
}

// A non-negative integer (ids) or, with `allow_none`, -1 too.
bool parseId(const YAML::Node& node, bool allow_none, int* id) {
  double v = 0.0;
  if (!scalarNumber(node, &v) || v != std::floor(v) || v < (allow_none ? -1 : 0) ||
      v > std::numeric_limits<int>::max()) {
    return false;
  }
  *id = static_cast<int>(v);
  return true;
}

Problem parseEntryId(const Fields& fields, int* id) {
  const YAML::Node& node = fields.at("id");
  if (!parseId(node, false, id)) {
    return at(node, "id must be a non-negative integer, got " + describe(node));
  }
  return {};
}

Problem parseFinite(const Fields& fields, const std::string& key, double* value) {
  const YAML::Node& node = fields.at(key);
  if (!scalarNumber(node, value) || !std::isfinite(*value)) {
    return at(node, key + " must be a finite number, got " + describe(node));
  }
  return {};
}

// A direction within [-π, π] (what the filter's normal form holds).
Problem parseAngle(const Fields& fields, double* theta) {
  const Problem problem = parseFinite(fields, "theta", theta);
  if (!problem.none()) return problem;
  const YAML::Node& node = fields.at("theta");
  if (std::abs(*theta) > kPi) return at(node, "theta must lie in [-pi, pi], got " + describe(node));
  return {};
}

Problem parseObservations(const Fields& fields, int* observations) {
  if (!fields.count("observations")) return {};
  const YAML::Node& node = fields.at("observations");
  double n = 0.0;
  if (!scalarNumber(node, &n) || n != std::floor(n) || n < 1 || n > 1e9) {
    return at(node, "observations must be an integer >= 1, got " + describe(node));
  }
  *observations = static_cast<int>(n);
  return {};
}

// A list [a, b, ...] of finite numbers; the problem names `key`.
Problem parseList(const std::string& key, const YAML::Node& node, std::vector<double>* values) {
  if (!node.IsSequence()) return at(node, key + " must be a list [..], got " + describe(node));
  for (const YAML::Node& item : node) {
    double v = 0.0;
    if (!scalarNumber(item, &v) || !std::isfinite(v)) {
      return at(item, key + " entries must be finite numbers, got " + describe(item));
    }
    values->push_back(v);
  }
  return {};
}

// The 2×2 covariance [a, ab, ba, b] (or [a, ab, b]); symmetric positive
// definite, its diagonal within `max_first` and `max_second`.
Problem parseCovariance(const Fields& fields, double max_first, double max_second,
                        const std::string& bound_text, Matrix2* out) {
  const YAML::Node& node = fields.at("covariance");
  std::vector<double> values;
  const Problem problem = parseList("covariance", node, &values);
  if (!problem.none()) return problem;
  Matrix2 c;
  if (values.size() == 4) {
    c << values[0], values[1], values[2], values[3];
  } else if (values.size() == 3) {
    c << values[0], values[1], values[1], values[2];
  } else {
    return at(node, "covariance needs 4 values (row-major 2x2; or 3: upper triangle), got " +
                        std::to_string(values.size()));
  }
  if (c(0, 0) > max_first || c(1, 1) > max_second)
    return at(node, "covariance beyond " + bound_text);
  if (std::abs(c(0, 1) - c(1, 0)) > 1e-9 * (1.0 + c.cwiseAbs().maxCoeff())) {
    return at(node, "covariance is not symmetric");
  }
  if (!(c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0)) {
    return at(node, "covariance is not positive definite");
  }
  *out = c;
  return {};
}

// The bounds as the errors name them.
std::string coordinateBound() { return std::to_string(static_cast<long>(kMaxLandmarkCoordinate)); }
std::string varianceBound() {
  return std::to_string(static_cast<long>(kMaxLandmarkVariance)) +
         " m^2 (a landmark known to no better than a kilometre)";
}
constexpr char kAngleVarianceBound[] = "pi^2 rad^2 (a direction not known at all)";

// One point entry {id: .., x: .., ...}.
Problem parsePoint(const YAML::Node& entry, LandmarkRecord* out) {
  Fields fields;
  Problem problem = readFields(entry, {"id", "x", "y", "covariance", "observations"},
                               {"id", "x", "y", "covariance"}, &fields);
  if (!problem.none()) return problem;
  LandmarkRecord r;
  // Every check runs (in order); the first problem is the one reported.
  for (const Problem& step :
       {parseEntryId(fields, &r.id), parseFinite(fields, "x", &r.position.x()),
        parseFinite(fields, "y", &r.position.y()), parseObservations(fields, &r.observations)}) {
    if (!step.none()) return step;
  }
  if (std::abs(r.position.x()) > kMaxLandmarkCoordinate ||
      std::abs(r.position.y()) > kMaxLandmarkCoordinate) {
    return at(entry, "position beyond " + coordinateBound() + " m from the origin");
  }
  problem = parseCovariance(fields, kMaxLandmarkVariance, kMaxLandmarkVariance, varianceBound(),
                            &r.covariance);
  if (!problem.none()) return problem;
  *out = r;
  return {};
}

// One (p, θ) line entry.
Problem parseLine(const YAML::Node& entry, LineLandmarkRecord* out) {
  Fields fields;
  Problem problem = readFields(entry, {"id", "p", "theta", "covariance", "observations", "extent"},
                               {"id", "p", "theta", "covariance"}, &fields);
  if (!problem.none()) return problem;
  LineLandmarkRecord r;
  for (const Problem& step :
       {parseEntryId(fields, &r.id), parseFinite(fields, "p", &r.p), parseAngle(fields, &r.theta),
        parseObservations(fields, &r.observations)}) {
    if (!step.none()) return step;
  }
  const YAML::Node& p = fields.at("p");
  if (r.p < 0.0) return at(p, "p must be >= 0 (the normal form), got " + describe(p));
  if (r.p > kMaxLandmarkCoordinate) return at(p, "p beyond " + coordinateBound() + " m");
  problem = parseCovariance(fields, kMaxLandmarkVariance, kMaxLandmarkAngleVariance,
                            varianceBound() + " or " + kAngleVarianceBound, &r.covariance);
  if (!problem.none()) return problem;
  if (fields.count("extent")) {
    const YAML::Node& node = fields.at("extent");
    std::vector<double> extent;
    problem = parseList("extent", node, &extent);
    if (!problem.none()) return problem;
    if (extent.size() != 2) return at(node, "extent needs 2 values [s_min, s_max]");
    if (!(extent[0] <= extent[1])) return at(node, "extent has s_min > s_max");
    if (std::abs(extent[0]) > kMaxLandmarkCoordinate ||
        std::abs(extent[1]) > kMaxLandmarkCoordinate) {
      return at(node, "extent beyond " + coordinateBound() + " m");
    }
    r.has_extent = true;
    r.s_min = extent[0];
    r.s_max = extent[1];
  }
  *out = r;
  return {};
}

// One θ-only line entry (its endpoint ids are checked against the points
// once the whole file is read).
Problem parseLineAngle(const YAML::Node& entry, LineAngleRecord* out) {
  Fields fields;
  Problem problem = readFields(entry, {"id", "theta", "variance", "observations", "endpoints"},
                               {"id", "theta", "variance"}, &fields);
  if (!problem.none()) return problem;
  LineAngleRecord r;
  for (const Problem& step :
       {parseEntryId(fields, &r.id), parseAngle(fields, &r.theta),
        parseFinite(fields, "variance", &r.variance), parseObservations(fields, &r.observations)}) {
    if (!step.none()) return step;
  }
  const YAML::Node& variance = fields.at("variance");
  if (!(r.variance > 0.0)) {
    return at(variance, "variance must be positive, got " + describe(variance));
  }
  if (r.variance > kMaxLandmarkAngleVariance) {
    return at(variance, std::string("variance beyond ") + kAngleVarianceBound);
  }
  if (fields.count("endpoints")) {
    const YAML::Node& node = fields.at("endpoints");
    if (!node.IsSequence() || node.size() != 2 || !parseId(node[0], true, &r.endpoint_ids[0]) ||
        !parseId(node[1], true, &r.endpoint_ids[1])) {
      return at(node,
                "endpoints must be two point ids [a, b] (-1: none), got " +
                    (node.IsSequence() ? std::to_string(node.size()) + " values" : describe(node)));
    }
    if (r.endpoint_ids[0] >= 0 && r.endpoint_ids[0] == r.endpoint_ids[1]) {
      return at(node, "endpoints name point " + std::to_string(r.endpoint_ids[0]) + " twice");
    }
  }
  *out = r;
  return {};
}

}  // namespace

std::string formatLandmarkMap(const LandmarkMapFile& map) {
  std::ostringstream out;
  out.precision(17);  // enough digits for an exact double round trip
  out << "# EKF-SLAM landmarks in the frame below. Points: x, y in m, covariance = the\n"
         "# full 2x2 marginal [xx, xy, yx, yy] in m^2. Lines: x cos(theta) + y sin(theta)\n"
         "# = p (m, rad), covariance of (p, theta), extent = the seen stretch [s_min,\n"
         "# s_max] in m along (-sin(theta), cos(theta)) from the foot point. Line angles:\n"
         "# theta alone (variance in rad^2), offset from the endpoint points (-1: none).\n"
         "# observations = sightings (1: tentative).\n"
      << "version: " << kLandmarkMapVersion << "\n"
      << "frame: " << io_yaml::scalarText(map.frame) << "\n"
      << "count: " << map.size() << "\n";
  auto writeCovariance = [&out](const Matrix2& c) {
    out << "covariance: [" << c(0, 0) << ", " << c(0, 1) << ", " << c(1, 0) << ", " << c(1, 1)
        << "]";
  };
  out << "landmarks:" << (map.landmarks.empty() ? " []" : "") << "\n";
  for (const LandmarkRecord& r : map.landmarks) {
    out << "  - {id: " << r.id << ", x: " << r.position.x() << ", y: " << r.position.y() << ", ";
    writeCovariance(r.covariance);
    out << ", observations: " << r.observations << "}\n";
  }
  out << "lines:" << (map.lines.empty() ? " []" : "") << "\n";
  for (const LineLandmarkRecord& r : map.lines) {
    out << "  - {id: " << r.id << ", p: " << r.p << ", theta: " << r.theta << ", ";
    writeCovariance(r.covariance);
    out << ", observations: " << r.observations;
    if (r.has_extent) out << ", extent: [" << r.s_min << ", " << r.s_max << "]";
    out << "}\n";
  }
  out << "line_angles:" << (map.line_angles.empty() ? " []" : "") << "\n";
  for (const LineAngleRecord& r : map.line_angles) {
    out << "  - {id: " << r.id << ", theta: " << r.theta << ", variance: " << r.variance
        << ", observations: " << r.observations << ", endpoints: [" << r.endpoint_ids[0] << ", "
        << r.endpoint_ids[1] << "]}\n";
  }
  return out.str();
}

std::string writeLandmarkMap(const std::string& path, const LandmarkMapFile& map) {
  return writeFileAtomically(path, formatLandmarkMap(map));
}

namespace {

// The tree of a landmark map file into `result`.
Problem readTree(const YAML::Node& root, LandmarkMapFile* result) {
  if (root.IsNull()) return {0, "no 'landmarks:' list"};
  if (!root.IsMap()) {
    return at(root, "expected keys (version, frame, count, landmarks, ...), got " + describe(root));
  }
  std::set<std::string> seen;
  std::set<int> ids;
  int version = 0;                    // 0: a file from before the version key
  long count = -1;                    // -1: not given
  std::vector<int> line_angle_lines;  // file line of each line_angles entry
  for (const auto& pair : root) {
    const YAML::Node &key_node = pair.first, &value = pair.second;
    if (!key_node.IsScalar()) return at(key_node, "expected a key, got " + describe(key_node));
    const std::string& key = key_node.Scalar();
    const bool is_list = key == "landmarks" || key == "lines" || key == "line_angles";
    if (!is_list && key != "frame" && key != "version" && key != "count") {
      return at(key_node, "unknown key '" + key + "'");
    }
    if (!seen.insert(key).second) return at(key_node, "'" + key + ":' given twice");
    if (key == "frame") {
      if (!value.IsNull() && !value.IsScalar()) {
        return at(value, "frame must be a frame id, got " + describe(value));
      }
      if (value.Scalar().empty()) return at(key_node, "frame must not be empty");
      result->frame = value.Scalar();
    } else if (key == "version") {
      double v = 0.0;
      if (!scalarNumber(value, &v) || v != std::floor(v) || v < 1) {
        return at(value, "version must be a positive integer, got " + describe(value));
      }
      if (v > kLandmarkMapVersion) {
        return at(value, "format version " + value.Scalar() +
                             " is newer than this program reads (" +
                             std::to_string(kLandmarkMapVersion) + ")");
      }
      version = static_cast<int>(v);
    } else if (key == "count") {
      double v = 0.0;
      if (!scalarNumber(value, &v) || v != std::floor(v) || v < 0 || v > 1e8) {
        return at(value, "count must be a landmark count, got " + describe(value));
      }
      count = static_cast<long>(v);
    } else if (!value.IsNull() && !value.IsSequence()) {  // `landmarks:` alone: none
      return at(value, "'" + key + ":' must be followed by a list");
    } else {
      for (const YAML::Node& entry : value) {
        Problem problem;
        int id = -1;
        if (key == "landmarks") {
          LandmarkRecord r;
          problem = parsePoint(entry, &r);
          id = r.id;
          if (problem.none()) result->landmarks.push_back(r);
        } else if (key == "lines") {
          LineLandmarkRecord r;
          problem = parseLine(entry, &r);
          id = r.id;
          if (problem.none()) result->lines.push_back(r);
        } else {
          LineAngleRecord r;
          problem = parseLineAngle(entry, &r);
          id = r.id;
          if (problem.none()) {
            result->line_angles.push_back(r);
            line_angle_lines.push_back(lineOf(entry));
          }
        }
        if (!problem.none()) return problem;
        if (!ids.insert(id).second) return at(entry, "id " + std::to_string(id) + " appears twice");
      }
    }
  }
  const bool has_lines = seen.count("lines"), has_line_angles = seen.count("line_angles");
  if (!seen.count("landmarks")) return {0, "no 'landmarks:' list"};
  if (version < 2 && (has_lines || has_line_angles)) {
    return {0, "'lines:' and 'line_angles:' need 'version: 2'"};
  }
  if (version >= 2 && !(has_lines && has_line_angles)) {
    return {0, std::string("no '") + (has_lines ? "line_angles" : "lines") +
                   ":' list (required from version 2; the file is cut short or edited)"};
  }
  if (version >= 1 && count < 0) return {0, "no 'count:' (required from version 1)"};
  if (count >= 0 && count != static_cast<long>(result->size())) {
    return {0, std::to_string(result->size()) + " landmarks where 'count' says " +
                   std::to_string(count) + " (the file is cut short or edited)"};
  }
  std::set<int> point_ids;
  for (const LandmarkRecord& r : result->landmarks) point_ids.insert(r.id);
  for (size_t i = 0; i < result->line_angles.size(); ++i) {
    for (int endpoint : result->line_angles[i].endpoint_ids) {
      if (endpoint >= 0 && !point_ids.count(endpoint)) {
        return {line_angle_lines[i],
                "endpoint " + std::to_string(endpoint) + " is not a point landmark of this file"};
      }
    }
  }
  return {};
}

}  // namespace

std::string parseLandmarkMap(const std::string& text, const std::string& source,
                             LandmarkMapFile* map) {
  auto fail = [&source](const Problem& problem) {
    return source + (problem.line > 0 ? ":" + std::to_string(problem.line) : "") + ": " +
           problem.text;
  };
  Problem problem;
  YAML::Node root;
  problem.text = io_yaml::loadDocument(text, &root, &problem.line);
  if (!problem.none()) return fail(problem);
  LandmarkMapFile result;
  try {
    problem = readTree(root, &result);
  } catch (const YAML::Exception& e) {  // not expected: readTree asks only what nodes hold
    problem = {e.mark.is_null() ? 0 : e.mark.line + 1, e.msg};
  }
  if (!problem.none()) return fail(problem);
  *map = result;
  return "";
}

std::string readLandmarkMap(const std::string& path, LandmarkMapFile* map) {
  std::ifstream in(path);
  if (!in) return path + ": cannot open";
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parseLandmarkMap(buffer.str(), path, map);
}

}  // namespace ekf_slam
