#include "ekf_slam_core/eval/relations.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

namespace ekf_slam {
namespace {

ErrorStats stats(const std::vector<double>& values) {
  ErrorStats s;
  if (values.empty()) return s;
  double sum = 0.0;
  for (double v : values) sum += v;
  s.mean = sum / values.size();
  double sq = 0.0;
  for (double v : values) sq += (v - s.mean) * (v - s.mean);
  s.stddev = values.size() > 1 ? std::sqrt(sq / (values.size() - 1)) : 0.0;
  return s;
}

bool isContentLine(const std::string& line) {
  const size_t first = line.find_first_not_of(" \t\r");
  return first != std::string::npos && line[first] != '#';
}

// Reads the content lines of `path` (comments and blank lines skipped) with
// `parse`, which returns an empty string or the problem with that line. On
// any error `out` is left untouched: no partial result.
template <typename T, typename Parse>
std::string readRecords(const std::string& path, std::vector<T>* out, Parse parse) {
  std::ifstream in(path);
  if (!in) return path + ": cannot open";
  std::vector<T> records;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!isContentLine(line)) continue;
    std::istringstream fields(line);
    T record;
    const std::string problem = parse(fields, &record);
    if (!problem.empty()) return path + ":" + std::to_string(number) + ": " + problem;
    records.push_back(record);
  }
  *out = std::move(records);
  return "";
}

}  // namespace

std::string readRelations(const std::string& path, std::vector<Relation>* out) {
  return readRecords(path, out, [](std::istringstream& fields, Relation* r) -> std::string {
    double x, y, z, roll, pitch, yaw;
    if (!(fields >> r->t1 >> r->t2 >> x >> y >> z >> roll >> pitch >> yaw)) {
      return "expected 't1 t2 x y z roll pitch yaw'";
    }
    r->motion = Pose2(x, y, yaw);
    return "";
  });
}

RelationErrors evaluateRelations(const std::vector<Relation>& relations,
                                 const std::vector<StampedPose>& trajectory,
                                 double stamp_tolerance) {
  // Sorted copy for lookup (the trajectory itself may not be monotonic).
  std::vector<StampedPose> sorted = trajectory;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  auto find = [&](double t, Pose2* pose) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), t,
                                     [](const StampedPose& p, double v) { return p.stamp < v; });
    double best = stamp_tolerance;
    bool found = false;
    for (auto c : {it, it == sorted.begin() ? it : it - 1}) {
      if (c == sorted.end()) continue;
      const double d = std::abs(c->stamp - t);
      if (d <= best) {
        best = d;
        *pose = c->pose;
        found = true;
      }
    }
    return found;
  };

  RelationErrors out;
  out.relations = static_cast<int>(relations.size());
  std::vector<double> t_sq, r_sq;
  for (const Relation& r : relations) {
    Pose2 a, b;
    if (!find(r.t1, &a) || !find(r.t2, &b)) continue;
    const Pose2 e = compose(inverse(r.motion), between(a, b));
    const double te = std::hypot(e.x, e.y), re = std::abs(wrapAngle(e.theta));
    out.translation_errors.push_back(te);
    out.rotation_errors.push_back(re);
    out.spans.push_back(std::abs(r.t2 - r.t1));
    t_sq.push_back(te * te);
    r_sq.push_back(re * re);
  }
  out.used = static_cast<int>(out.translation_errors.size());
  out.translation = stats(out.translation_errors);
  out.rotation = stats(out.rotation_errors);
  out.translation_squared = stats(t_sq);
  out.rotation_squared = stats(r_sq);
  return out;
}

std::vector<SpanBin> errorsBySpan(const RelationErrors& errors, const std::vector<double>& edges) {
  std::vector<SpanBin> bins(edges.size());
  for (size_t k = 0; k < edges.size(); ++k) {
    bins[k].from = edges[k];
    bins[k].to = k + 1 < edges.size() ? edges[k + 1] : std::numeric_limits<double>::infinity();
  }
  double total = 0.0;
  for (double t : errors.translation_errors) total += t;
  for (size_t i = 0; i < errors.spans.size(); ++i) {
    for (SpanBin& bin : bins) {
      if (errors.spans[i] < bin.from || errors.spans[i] >= bin.to) continue;
      ++bin.relations;
      bin.translation_mean += errors.translation_errors[i];
      bin.rotation_mean += errors.rotation_errors[i];
      break;
    }
  }
  for (SpanBin& bin : bins) {
    if (total > 0.0) bin.translation_share = bin.translation_mean / total;
    if (bin.relations == 0) continue;
    bin.translation_mean /= bin.relations;
    bin.rotation_mean /= bin.relations;
  }
  return bins;
}

}  // namespace ekf_slam
