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
#include "ekf_slam_core/io/text_fields.h"

namespace ekf_slam {
namespace {

using io_text::parseNumber;
using io_text::trim;

// Splits "a: 1, b: [1, 2], c: 3" at the commas outside brackets.
std::vector<std::string> splitTopLevel(const std::string& s) {
  std::vector<std::string> parts;
  int depth = 0;
  std::string current;
  for (char c : s) {
    if (c == '[') ++depth;
    if (c == ']') --depth;
    if (c == ',' && depth == 0) {
      parts.push_back(current);
      current.clear();
    } else {
      current += c;
    }
  }
  if (!trim(current).empty()) parts.push_back(current);
  return parts;
}

using Fields = std::map<std::string, std::string>;

// "key: value" pairs of one "- {..}" entry, each key once and known.
std::string splitFields(const std::string& body, std::initializer_list<const char*> known,
                        std::initializer_list<const char*> required, Fields* fields) {
  for (const std::string& part : splitTopLevel(body)) {
    const size_t colon = part.find(':');
    if (colon == std::string::npos) return "expected 'key: value', got '" + trim(part) + "'";
    const std::string key = trim(part.substr(0, colon));
    if (fields->count(key)) return "key '" + key + "' given twice";
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      return "unknown key '" + key + "'";
    }
    (*fields)[key] = trim(part.substr(colon + 1));
  }
  for (const char* key : required) {
    if (!fields->count(key)) return std::string("missing key '") + key + "'";
  }
  return "";
}

// A non-negative integer (ids) or, with `allow_none`, -1 too.
bool parseId(const std::string& text, bool allow_none, int* id) {
  double v = 0.0;
  if (!parseNumber(text, &v) || v != std::floor(v) || v < (allow_none ? -1 : 0) ||
      v > std::numeric_limits<int>::max()) {
    return false;
  }
  *id = static_cast<int>(v);
  return true;
}

std::string parseFinite(const Fields& fields, const std::string& key, double* value) {
  const std::string& text = fields.at(key);
  if (!parseNumber(text, value) || !std::isfinite(*value)) {
    return key + " must be a finite number, got '" + text + "'";
  }
  return "";
}

// A direction within [-π, π] (what the filter's normal form holds).
std::string parseAngle(const Fields& fields, double* theta) {
  const std::string problem = parseFinite(fields, "theta", theta);
  if (!problem.empty()) return problem;
  if (std::abs(*theta) > kPi)
    return "theta must lie in [-pi, pi], got '" + fields.at("theta") + "'";
  return "";
}

std::string parseObservations(const Fields& fields, int* observations) {
  if (!fields.count("observations")) return "";
  double n = 0.0;
  if (!parseNumber(fields.at("observations"), &n) || n != std::floor(n) || n < 1 || n > 1e9) {
    return "observations must be an integer >= 1, got '" + fields.at("observations") + "'";
  }
  *observations = static_cast<int>(n);
  return "";
}

// "[a, b, ...]" → its numbers, all finite; empty string or the problem,
// naming `key`.
std::string parseList(const std::string& key, const std::string& text,
                      std::vector<double>* values) {
  if (text.size() < 2 || text.front() != '[' || text.back() != ']') {
    return key + " must be a list [..], got '" + text + "'";
  }
  for (const std::string& item : splitTopLevel(text.substr(1, text.size() - 2))) {
    double v = 0.0;
    if (!parseNumber(item, &v) || !std::isfinite(v)) {
      return key + " entries must be finite numbers, got '" + trim(item) + "'";
    }
    values->push_back(v);
  }
  return "";
}

// The 2×2 covariance [a, ab, ba, b] (or [a, ab, b]); symmetric positive
// definite, its diagonal within `max_first` and `max_second`.
std::string parseCovariance(const Fields& fields, double max_first, double max_second,
                            const std::string& bound_text, Matrix2* out) {
  std::vector<double> values;
  const std::string problem = parseList("covariance", fields.at("covariance"), &values);
  if (!problem.empty()) return problem;
  Matrix2 c;
  if (values.size() == 4) {
    c << values[0], values[1], values[2], values[3];
  } else if (values.size() == 3) {
    c << values[0], values[1], values[1], values[2];
  } else {
    return "covariance needs 4 values (row-major 2x2; or 3: upper triangle), got " +
           std::to_string(values.size());
  }
  if (c(0, 0) > max_first || c(1, 1) > max_second) return "covariance beyond " + bound_text;
  if (std::abs(c(0, 1) - c(1, 0)) > 1e-9 * (1.0 + c.cwiseAbs().maxCoeff())) {
    return "covariance is not symmetric";
  }
  if (!(c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0)) {
    return "covariance is not positive definite";
  }
  *out = c;
  return "";
}

// The bounds as the errors name them.
std::string coordinateBound() { return std::to_string(static_cast<long>(kMaxLandmarkCoordinate)); }
std::string varianceBound() {
  return std::to_string(static_cast<long>(kMaxLandmarkVariance)) +
         " m^2 (a landmark known to no better than a kilometre)";
}
constexpr char kAngleVarianceBound[] = "pi^2 rad^2 (a direction not known at all)";

// One point "- {id: .., x: .., ...}" entry; empty string or the problem.
std::string parsePoint(const std::string& body, LandmarkRecord* out) {
  Fields fields;
  std::string problem = splitFields(body, {"id", "x", "y", "covariance", "observations"},
                                    {"id", "x", "y", "covariance"}, &fields);
  if (!problem.empty()) return problem;
  LandmarkRecord r;
  if (!parseId(fields["id"], false, &r.id)) {
    return "id must be a non-negative integer, got '" + fields["id"] + "'";
  }
  // Every check runs (in order); the first problem is the one reported.
  for (const auto& step :
       {parseFinite(fields, "x", &r.position.x()), parseFinite(fields, "y", &r.position.y()),
        parseObservations(fields, &r.observations)}) {
    if (!step.empty()) return step;
  }
  if (std::abs(r.position.x()) > kMaxLandmarkCoordinate ||
      std::abs(r.position.y()) > kMaxLandmarkCoordinate) {
    return "position beyond " + coordinateBound() + " m from the origin";
  }
  problem = parseCovariance(fields, kMaxLandmarkVariance, kMaxLandmarkVariance, varianceBound(),
                            &r.covariance);
  if (!problem.empty()) return problem;
  *out = r;
  return "";
}

// One (p, θ) line entry.
std::string parseLine(const std::string& body, LineLandmarkRecord* out) {
  Fields fields;
  std::string problem =
      splitFields(body, {"id", "p", "theta", "covariance", "observations", "extent"},
                  {"id", "p", "theta", "covariance"}, &fields);
  if (!problem.empty()) return problem;
  LineLandmarkRecord r;
  if (!parseId(fields["id"], false, &r.id)) {
    return "id must be a non-negative integer, got '" + fields["id"] + "'";
  }
  for (const auto& step : {parseFinite(fields, "p", &r.p), parseAngle(fields, &r.theta),
                           parseObservations(fields, &r.observations)}) {
    if (!step.empty()) return step;
  }
  if (r.p < 0.0) return "p must be >= 0 (the normal form), got '" + fields["p"] + "'";
  if (r.p > kMaxLandmarkCoordinate) return "p beyond " + coordinateBound() + " m";
  problem = parseCovariance(fields, kMaxLandmarkVariance, kMaxLandmarkAngleVariance,
                            varianceBound() + " or " + kAngleVarianceBound, &r.covariance);
  if (!problem.empty()) return problem;
  if (fields.count("extent")) {
    std::vector<double> extent;
    problem = parseList("extent", fields["extent"], &extent);
    if (!problem.empty()) return problem;
    if (extent.size() != 2) return "extent needs 2 values [s_min, s_max]";
    if (!(extent[0] <= extent[1])) return "extent has s_min > s_max";
    if (std::abs(extent[0]) > kMaxLandmarkCoordinate ||
        std::abs(extent[1]) > kMaxLandmarkCoordinate) {
      return "extent beyond " + coordinateBound() + " m";
    }
    r.has_extent = true;
    r.s_min = extent[0];
    r.s_max = extent[1];
  }
  *out = r;
  return "";
}

// One θ-only line entry (its endpoint ids are checked against the points
// once the whole file is read).
std::string parseLineAngle(const std::string& body, LineAngleRecord* out) {
  Fields fields;
  std::string problem = splitFields(body, {"id", "theta", "variance", "observations", "endpoints"},
                                    {"id", "theta", "variance"}, &fields);
  if (!problem.empty()) return problem;
  LineAngleRecord r;
  if (!parseId(fields["id"], false, &r.id)) {
    return "id must be a non-negative integer, got '" + fields["id"] + "'";
  }
  for (const auto& step :
       {parseAngle(fields, &r.theta), parseFinite(fields, "variance", &r.variance),
        parseObservations(fields, &r.observations)}) {
    if (!step.empty()) return step;
  }
  if (!(r.variance > 0.0)) return "variance must be positive, got '" + fields["variance"] + "'";
  if (r.variance > kMaxLandmarkAngleVariance)
    return std::string("variance beyond ") + kAngleVarianceBound;
  if (fields.count("endpoints")) {
    const std::string& list = fields["endpoints"];
    std::vector<std::string> items;
    if (list.size() >= 2 && list.front() == '[' && list.back() == ']') {
      items = splitTopLevel(list.substr(1, list.size() - 2));
    }
    if (items.size() != 2 || !parseId(items[0], true, &r.endpoint_ids[0]) ||
        !parseId(items[1], true, &r.endpoint_ids[1])) {
      return "endpoints must be two point ids [a, b] (-1: none), got '" + list + "'";
    }
    if (r.endpoint_ids[0] >= 0 && r.endpoint_ids[0] == r.endpoint_ids[1]) {
      return "endpoints name point " + std::to_string(r.endpoint_ids[0]) + " twice";
    }
  }
  *out = r;
  return "";
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
      << "frame: " << map.frame << "\n"
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

std::string parseLandmarkMap(const std::string& text, const std::string& source,
                             LandmarkMapFile* map) {
  enum class List { kNone, kPoints, kLines, kLineAngles };
  LandmarkMapFile result;
  std::set<int> ids;
  List in_list = List::kNone;
  bool seen_points = false, seen_lines = false, seen_line_angles = false;
  int version = 0;                    // 0: a file from before the version key
  long count = -1;                    // -1: not given
  std::vector<int> line_angle_lines;  // file line of each line_angles entry
  std::istringstream in(text);
  std::string raw;
  int line_number = 0;
  auto fail = [&](const std::string& problem) {
    return source + ":" + std::to_string(line_number) + ": " + problem;
  };
  while (std::getline(in, raw)) {
    ++line_number;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    if (line.rfind("- ", 0) == 0) {
      if (in_list == List::kNone) {
        return fail("a list entry outside 'landmarks:', 'lines:' or 'line_angles:'");
      }
      const std::string entry = trim(line.substr(2));
      if (entry.size() < 2 || entry.front() != '{' || entry.back() != '}') {
        return fail("expected '- {id: .., ...}'");
      }
      const std::string body = entry.substr(1, entry.size() - 2);
      std::string problem;
      int id = -1;
      if (in_list == List::kPoints) {
        LandmarkRecord r;
        problem = parsePoint(body, &r);
        id = r.id;
        if (problem.empty()) result.landmarks.push_back(r);
      } else if (in_list == List::kLines) {
        LineLandmarkRecord r;
        problem = parseLine(body, &r);
        id = r.id;
        if (problem.empty()) result.lines.push_back(r);
      } else {
        LineAngleRecord r;
        problem = parseLineAngle(body, &r);
        id = r.id;
        if (problem.empty()) {
          result.line_angles.push_back(r);
          line_angle_lines.push_back(line_number);
        }
      }
      if (!problem.empty()) return fail(problem);
      if (!ids.insert(id).second) return fail("id " + std::to_string(id) + " appears twice");
      continue;
    }
    const size_t colon = line.find(':');
    if (colon == std::string::npos) return fail("expected 'key: value', got '" + line + "'");
    const std::string key = trim(line.substr(0, colon));
    const std::string value = trim(line.substr(colon + 1));
    in_list = List::kNone;
    if (key == "frame") {
      if (value.empty()) return fail("frame must not be empty");
      result.frame = value;
    } else if (key == "version") {
      double v = 0.0;
      if (!parseNumber(value, &v) || v != std::floor(v) || v < 1) {
        return fail("version must be a positive integer, got '" + value + "'");
      }
      if (v > kLandmarkMapVersion) {
        return fail("format version " + value + " is newer than this program reads (" +
                    std::to_string(kLandmarkMapVersion) + ")");
      }
      version = static_cast<int>(v);
    } else if (key == "count") {
      double v = 0.0;
      if (!parseNumber(value, &v) || v != std::floor(v) || v < 0 || v > 1e8) {
        return fail("count must be a landmark count, got '" + value + "'");
      }
      count = static_cast<long>(v);
    } else if (key == "landmarks" || key == "lines" || key == "line_angles") {
      const List list = key == "landmarks" ? List::kPoints
                        : key == "lines"   ? List::kLines
                                           : List::kLineAngles;
      bool& seen = list == List::kPoints  ? seen_points
                   : list == List::kLines ? seen_lines
                                          : seen_line_angles;
      if (seen) return fail("'" + key + ":' given twice");
      seen = true;
      if (value.empty()) {
        in_list = list;
      } else if (value != "[]") {
        return fail("'" + key + ":' must be followed by a list");
      }
    } else {
      return fail("unknown key '" + key + "'");
    }
  }
  if (!seen_points) return source + ": no 'landmarks:' list";
  if (version < 2 && (seen_lines || seen_line_angles)) {
    return source + ": 'lines:' and 'line_angles:' need 'version: 2'";
  }
  if (version >= 2 && !(seen_lines && seen_line_angles)) {
    return source + ": no '" + (seen_lines ? "line_angles" : "lines") +
           ":' list (required from version 2; the file is cut short or edited)";
  }
  if (version >= 1 && count < 0) return source + ": no 'count:' (required from version 1)";
  if (count >= 0 && count != static_cast<long>(result.size())) {
    return source + ": " + std::to_string(result.size()) + " landmarks where 'count' says " +
           std::to_string(count) + " (the file is cut short or edited)";
  }
  std::set<int> point_ids;
  for (const LandmarkRecord& r : result.landmarks) point_ids.insert(r.id);
  for (size_t i = 0; i < result.line_angles.size(); ++i) {
    for (int endpoint : result.line_angles[i].endpoint_ids) {
      if (endpoint >= 0 && !point_ids.count(endpoint)) {
        return source + ":" + std::to_string(line_angle_lines[i]) + ": endpoint " +
               std::to_string(endpoint) + " is not a point landmark of this file";
      }
    }
  }
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
