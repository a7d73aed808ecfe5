#include "ekf_slam_core/io/landmark_map.h"

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
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

// One "- {id: .., x: .., ...}" entry; empty string or the problem.
std::string parseEntry(const std::string& body, LandmarkRecord* out) {
  std::map<std::string, std::string> fields;
  for (const std::string& part : splitTopLevel(body)) {
    const size_t colon = part.find(':');
    if (colon == std::string::npos) return "expected 'key: value', got '" + trim(part) + "'";
    const std::string key = trim(part.substr(0, colon));
    if (fields.count(key)) return "key '" + key + "' given twice";
    fields[key] = trim(part.substr(colon + 1));
  }
  for (const auto& [key, value] : fields) {
    if (key != "id" && key != "x" && key != "y" && key != "covariance" && key != "observations") {
      return "unknown key '" + key + "'";
    }
  }
  for (const char* key : {"id", "x", "y", "covariance"}) {
    if (!fields.count(key)) return std::string("missing key '") + key + "'";
  }
  LandmarkRecord r;
  double id = 0.0;
  if (!parseNumber(fields["id"], &id) || id != std::floor(id) || id < 0 ||
      id > std::numeric_limits<int>::max()) {
    return "id must be a non-negative integer, got '" + fields["id"] + "'";
  }
  r.id = static_cast<int>(id);
  if (!parseNumber(fields["x"], &r.position.x()) || !std::isfinite(r.position.x())) {
    return "x must be a finite number, got '" + fields["x"] + "'";
  }
  if (!parseNumber(fields["y"], &r.position.y()) || !std::isfinite(r.position.y())) {
    return "y must be a finite number, got '" + fields["y"] + "'";
  }
  if (fields.count("observations")) {
    double n = 0.0;
    if (!parseNumber(fields["observations"], &n) || n != std::floor(n) || n < 1 || n > 1e9) {
      return "observations must be an integer >= 1, got '" + fields["observations"] + "'";
    }
    r.observations = static_cast<int>(n);
  }
  const std::string& cov = fields["covariance"];
  if (cov.size() < 2 || cov.front() != '[' || cov.back() != ']') {
    return "covariance must be a list [xx, xy, yx, yy] or [xx, xy, yy], got '" + cov + "'";
  }
  std::vector<double> values;
  for (const std::string& item : splitTopLevel(cov.substr(1, cov.size() - 2))) {
    double v = 0.0;
    if (!parseNumber(item, &v) || !std::isfinite(v)) {
      return "covariance entries must be finite numbers, got '" + trim(item) + "'";
    }
    values.push_back(v);
  }
  if (values.size() == 4) {
    r.covariance << values[0], values[1], values[2], values[3];
  } else if (values.size() == 3) {
    r.covariance << values[0], values[1], values[1], values[2];
  } else {
    return "covariance needs 4 values [xx, xy, yx, yy] (or 3: [xx, xy, yy]), got " +
           std::to_string(values.size());
  }
  if (std::abs(r.position.x()) > kMaxLandmarkCoordinate ||
      std::abs(r.position.y()) > kMaxLandmarkCoordinate) {
    return "position beyond " + std::to_string(static_cast<long>(kMaxLandmarkCoordinate)) +
           " m from the origin";
  }
  const Matrix2& c = r.covariance;
  if (c(0, 0) > kMaxLandmarkVariance || c(1, 1) > kMaxLandmarkVariance) {
    return "covariance beyond " + std::to_string(static_cast<long>(kMaxLandmarkVariance)) +
           " m^2 (a landmark known to no better than a kilometre)";
  }
  if (std::abs(c(0, 1) - c(1, 0)) > 1e-9 * (1.0 + c.cwiseAbs().maxCoeff())) {
    return "covariance is not symmetric";
  }
  if (!(c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0)) {
    return "covariance is not positive definite";
  }
  *out = r;
  return "";
}

}  // namespace

std::string formatLandmarkMap(const LandmarkMapFile& map) {
  std::ostringstream out;
  out.precision(17);  // enough digits for an exact double round trip
  out << "# EKF-SLAM point landmarks: x, y in m (frame below); covariance = the full 2x2\n"
         "# marginal [xx, xy, yx, yy] in m^2; observations = sightings (1: tentative).\n"
      << "version: " << kLandmarkMapVersion << "\n"
      << "frame: " << map.frame << "\n"
      << "count: " << map.landmarks.size() << "\n"
      << "landmarks:" << (map.landmarks.empty() ? " []" : "") << "\n";
  for (const LandmarkRecord& r : map.landmarks) {
    const Matrix2& c = r.covariance;
    out << "  - {id: " << r.id << ", x: " << r.position.x() << ", y: " << r.position.y()
        << ", covariance: [" << c(0, 0) << ", " << c(0, 1) << ", " << c(1, 0) << ", " << c(1, 1)
        << "], observations: " << r.observations << "}\n";
  }
  return out.str();
}

std::string writeLandmarkMap(const std::string& path, const LandmarkMapFile& map) {
  return writeFileAtomically(path, formatLandmarkMap(map));
}

std::string parseLandmarkMap(const std::string& text, const std::string& source,
                             LandmarkMapFile* map) {
  LandmarkMapFile result;
  std::set<int> ids;
  bool in_list = false, seen_list = false;
  int version = 0;  // 0: a file from before the version key
  long count = -1;  // -1: not given
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
      if (!in_list) return fail("a list entry outside 'landmarks:'");
      const std::string entry = trim(line.substr(2));
      if (entry.size() < 2 || entry.front() != '{' || entry.back() != '}') {
        return fail("expected '- {id: .., x: .., y: .., covariance: [..]}'");
      }
      LandmarkRecord r;
      const std::string problem = parseEntry(entry.substr(1, entry.size() - 2), &r);
      if (!problem.empty()) return fail(problem);
      if (!ids.insert(r.id).second) return fail("id " + std::to_string(r.id) + " appears twice");
      result.landmarks.push_back(r);
      continue;
    }
    const size_t colon = line.find(':');
    if (colon == std::string::npos) return fail("expected 'key: value', got '" + line + "'");
    const std::string key = trim(line.substr(0, colon));
    const std::string value = trim(line.substr(colon + 1));
    in_list = false;
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
    } else if (key == "landmarks") {
      if (value == "[]") {
        seen_list = true;
      } else if (value.empty()) {
        in_list = seen_list = true;
      } else {
        return fail("'landmarks:' must be followed by a list");
      }
    } else {
      return fail("unknown key '" + key + "'");
    }
  }
  if (!seen_list) return source + ": no 'landmarks:' list";
  if (version >= 1 && count < 0) return source + ": no 'count:' (required from version 1)";
  if (count >= 0 && count != static_cast<long>(result.landmarks.size())) {
    return source + ": " + std::to_string(result.landmarks.size()) +
           " landmarks where 'count' says " + std::to_string(count) +
           " (the file is cut short or edited)";
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
