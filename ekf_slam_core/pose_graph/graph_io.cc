#include "ekf_slam_core/pose_graph/graph_io.h"

#include <cstdio>
#include <fstream>
#include <sstream>

namespace ekf_slam {

namespace {

// "%.17g": the shortest format that reads back as the same double.
class Writer {
 public:
  explicit Writer(const std::string& path) : out_(path) {}
  bool ok() const { return static_cast<bool>(out_); }

  Writer& word(const char* text) {
    separate();
    out_ << text;
    return *this;
  }
  Writer& number(double value) {
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.17g", value);
    return word(buffer);
  }
  Writer& integer(long value) {
    separate();
    out_ << value;
    return *this;
  }
  Writer& pose(const Pose2& p) { return number(p.x).number(p.y).number(p.theta); }
  template <int N>
  Writer& matrix(const Eigen::Matrix<double, N, N>& m) {
    for (int i = 0; i < N; ++i) {
      for (int j = 0; j < N; ++j) number(m(i, j));
    }
    return *this;
  }
  void end() {
    out_ << '\n';
    first_ = true;
  }
  void comment(const std::string& text) { out_ << "# " << text << '\n'; }

  std::string finish(const std::string& path) {
    out_.flush();
    return out_ ? "" : path + ": write error";
  }

 private:
  void separate() {
    if (!first_) out_ << ' ';
    first_ = false;
  }
  std::ofstream out_;
  bool first_ = true;
};

// One record's fields, read left to right; any failure sticks.
class Fields {
 public:
  explicit Fields(const std::string& line) : in_(line) {}
  bool ok() const { return ok_; }
  // True when nothing but blanks is left (after a successful read).
  bool done() {
    std::string rest;
    return ok_ && !(in_ >> rest);
  }

  double number() {
    double v = 0.0;
    if (!(in_ >> v)) ok_ = false;
    return v;
  }
  long integer() {
    long v = 0;
    if (!(in_ >> v)) ok_ = false;
    return v;
  }
  bool flag() {
    const long v = integer();
    if (v != 0 && v != 1) ok_ = false;
    return v == 1;
  }
  Pose2 pose() {
    Pose2 p;  // the fields as written: no re-wrapping of the heading
    p.x = number();
    p.y = number();
    p.theta = number();
    return p;
  }
  template <int N>
  Eigen::Matrix<double, N, N> matrix() {
    Eigen::Matrix<double, N, N> m;
    for (int i = 0; i < N; ++i) {
      for (int j = 0; j < N; ++j) m(i, j) = number();
    }
    return m;
  }
  RobustKernel kernel() {
    std::string name;
    if (!(in_ >> name)) ok_ = false;
    if (name == "none") return RobustKernel::kNone;
    if (name == "huber") return RobustKernel::kHuber;
    if (name == "cauchy") return RobustKernel::kCauchy;
    ok_ = false;
    return RobustKernel::kNone;
  }
  std::string keyword() {
    std::string word;
    in_ >> word;
    return word;
  }

 private:
  std::istringstream in_;
  bool ok_ = true;
};

const char* kernelName(RobustKernel kernel) {
  switch (kernel) {
    case RobustKernel::kNone:
      return "none";
    case RobustKernel::kHuber:
      return "huber";
    case RobustKernel::kCauchy:
      return "cauchy";
  }
  return "none";
}

// Calls record(keyword, fields) for each record line; it returns an error
// message (empty when fine). Returns the first error with its location.
template <typename Record>
std::string readRecords(const std::string& path, Record record) {
  std::ifstream in(path);
  if (!in) return path + ": cannot read";
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    Fields fields(line);
    const std::string keyword = fields.keyword();
    std::string error = record(keyword, fields);
    if (error.empty() && !fields.done()) error = "bad or missing values in " + keyword;
    if (!error.empty()) return path + ":" + std::to_string(number) + ": " + error;
  }
  if (in.bad()) return path + ": read error";
  return "";
}

}  // namespace

std::string savePoseGraph(const std::string& path, const PoseGraph& graph,
                          const PoseGraphOptions& options) {
  Writer w(path);
  if (!w.ok()) return path + ": cannot write";
  w.comment("ekf_slam pose graph (format: ekf_slam_core/pose_graph/graph_io.h)");
  w.word("POSE_GRAPH_OPTIONS")
      .integer(options.max_iterations)
      .number(options.convergence_step)
      .number(options.robust_kernel_width)
      .number(options.initial_lambda)
      .end();
  for (int i = 0; i < graph.nodeCount(); ++i) {
    w.word("NODE").integer(i).pose(graph.pose(i)).end();
  }
  for (const PoseGraphEdge& e : graph.edges()) {
    w.word("EDGE").integer(e.from).integer(e.to).pose(e.measurement).matrix(e.information);
    w.integer(e.robust ? 1 : 0).integer(e.active ? 1 : 0).end();
  }
  return w.finish(path);
}

std::string loadPoseGraph(const std::string& path, PoseGraph* graph, PoseGraphOptions* options) {
  PoseGraph loaded;
  PoseGraphOptions loaded_options;
  bool have_options = false;
  const std::string error = readRecords(path, [&](const std::string& keyword, Fields& f) {
    if (keyword == "POSE_GRAPH_OPTIONS") {
      loaded_options.max_iterations = static_cast<int>(f.integer());
      loaded_options.convergence_step = f.number();
      loaded_options.robust_kernel_width = f.number();
      loaded_options.initial_lambda = f.number();
      have_options = true;
    } else if (keyword == "NODE") {
      const long index = f.integer();
      const Pose2 pose = f.pose();
      if (!f.ok()) return std::string("bad NODE");
      if (index != loaded.nodeCount()) return std::string("NODE out of order");
      loaded.addNode(pose);
    } else if (keyword == "EDGE") {
      PoseGraphEdge e;
      e.from = static_cast<int>(f.integer());
      e.to = static_cast<int>(f.integer());
      e.measurement = f.pose();
      e.information = f.matrix<3>();
      e.robust = f.flag();
      e.active = f.flag();
      if (!f.ok()) return std::string("bad EDGE");
      if (e.from < 0 || e.from >= loaded.nodeCount() || e.to < 0 || e.to >= loaded.nodeCount()) {
        return std::string("EDGE refers to an unknown node");
      }
      loaded.addEdge(e);
    } else {
      return "unknown record " + keyword;
    }
    return std::string();
  });
  if (!error.empty()) return error;
  if (!have_options) return path + ": no POSE_GRAPH_OPTIONS";
  *graph = std::move(loaded);
  if (options) *options = loaded_options;
  return "";
}

std::string saveLandmarkGraph(const std::string& path, const LandmarkGraph& graph,
                              const LandmarkGraphOptions& options) {
  Writer w(path);
  if (!w.ok()) return path + ": cannot write";
  w.comment("ekf_slam landmark graph (format: ekf_slam_core/pose_graph/graph_io.h)");
  w.word("LANDMARK_GRAPH_OPTIONS")
      .integer(options.max_iterations)
      .number(options.convergence_step)
      .number(options.min_relative_decrease)
      .number(options.initial_lambda)
      .number(options.kernel_width)
      .end();
  w.word("LASER").pose(graph.laserPose()).end();
  for (int i = 0; i < graph.poseCount(); ++i) {
    w.word("POSE").integer(i).pose(graph.poses()[i]).integer(graph.isFixed(i) ? 1 : 0).end();
  }
  for (int j = 0; j < graph.landmarkCount(); ++j) {
    w.word("LANDMARK").integer(j).number(graph.landmarks()[j].x());
    w.number(graph.landmarks()[j].y()).end();
  }
  for (const RelativePoseEdge& e : graph.relativeEdges()) {
    w.word("RELATIVE").integer(e.from).integer(e.to).pose(e.from_offset).pose(e.to_offset);
    w.pose(e.measurement).matrix(e.information).word(kernelName(e.kernel)).end();
  }
  for (const PosePriorEdge& e : graph.priorEdges()) {
    w.word("PRIOR").integer(e.pose).pose(e.mean).matrix(e.information).end();
  }
  for (const ObservationEdge& e : graph.observationEdges()) {
    w.word("OBSERVATION").integer(e.pose).integer(e.landmark).number(e.z.range);
    w.number(e.z.bearing).matrix(e.information).word(kernelName(e.kernel)).end();
  }
  return w.finish(path);
}

std::string loadLandmarkGraph(const std::string& path, LandmarkGraph* graph,
                              LandmarkGraphOptions* options) {
  // The mount comes first in the file but is a constructor argument: the
  // records are collected, then the graph is built.
  LandmarkGraphOptions loaded_options;
  bool have_options = false, have_laser = false;
  Pose2 laser;
  std::vector<Pose2> poses;
  std::vector<char> fixed;
  std::vector<Vector2> landmarks;
  std::vector<RelativePoseEdge> relatives;
  std::vector<PosePriorEdge> priors;
  std::vector<ObservationEdge> observations;
  const std::string error = readRecords(path, [&](const std::string& keyword, Fields& f) {
    const long poses_so_far = static_cast<long>(poses.size());
    const long landmarks_so_far = static_cast<long>(landmarks.size());
    if (keyword == "LANDMARK_GRAPH_OPTIONS") {
      loaded_options.max_iterations = static_cast<int>(f.integer());
      loaded_options.convergence_step = f.number();
      loaded_options.min_relative_decrease = f.number();
      loaded_options.initial_lambda = f.number();
      loaded_options.kernel_width = f.number();
      have_options = true;
    } else if (keyword == "LASER") {
      laser = f.pose();
      have_laser = true;
    } else if (keyword == "POSE") {
      const long index = f.integer();
      const Pose2 pose = f.pose();
      const bool is_fixed = f.flag();
      if (!f.ok()) return std::string("bad POSE");
      if (index != poses_so_far) return std::string("POSE out of order");
      poses.push_back(pose);
      fixed.push_back(is_fixed ? 1 : 0);
    } else if (keyword == "LANDMARK") {
      const long index = f.integer();
      const double x = f.number(), y = f.number();
      if (!f.ok()) return std::string("bad LANDMARK");
      if (index != landmarks_so_far) return std::string("LANDMARK out of order");
      landmarks.emplace_back(x, y);
    } else if (keyword == "RELATIVE") {
      RelativePoseEdge e;
      e.from = static_cast<int>(f.integer());
      e.to = static_cast<int>(f.integer());
      e.from_offset = f.pose();
      e.to_offset = f.pose();
      e.measurement = f.pose();
      e.information = f.matrix<3>();
      e.kernel = f.kernel();
      if (!f.ok()) return std::string("bad RELATIVE");
      if (e.from < 0 || e.from >= poses_so_far || e.to < 0 || e.to >= poses_so_far) {
        return std::string("RELATIVE refers to an unknown pose");
      }
      relatives.push_back(e);
    } else if (keyword == "PRIOR") {
      PosePriorEdge e;
      e.pose = static_cast<int>(f.integer());
      e.mean = f.pose();
      e.information = f.matrix<3>();
      if (!f.ok()) return std::string("bad PRIOR");
      if (e.pose < 0 || e.pose >= poses_so_far) return std::string("PRIOR on an unknown pose");
      priors.push_back(e);
    } else if (keyword == "OBSERVATION") {
      ObservationEdge e;
      e.pose = static_cast<int>(f.integer());
      e.landmark = static_cast<int>(f.integer());
      e.z.range = f.number();
      e.z.bearing = f.number();
      e.information = f.matrix<2>();
      e.kernel = f.kernel();
      if (!f.ok()) return std::string("bad OBSERVATION");
      if (e.pose < 0 || e.pose >= poses_so_far || e.landmark < 0 ||
          e.landmark >= landmarks_so_far) {
        return std::string("OBSERVATION refers to an unknown pose or landmark");
      }
      observations.push_back(e);
    } else {
      return "unknown record " + keyword;
    }
    return std::string();
  });
  if (!error.empty()) return error;
  if (!have_options) return path + ": no LANDMARK_GRAPH_OPTIONS";
  if (!have_laser) return path + ": no LASER";
  LandmarkGraph loaded(laser);
  for (size_t i = 0; i < poses.size(); ++i) loaded.addPose(poses[i], fixed[i] != 0);
  for (const Vector2& m : landmarks) loaded.addLandmark(m);
  for (const RelativePoseEdge& e : relatives) loaded.addEdge(e);
  for (const PosePriorEdge& e : priors) loaded.addEdge(e);
  for (const ObservationEdge& e : observations) loaded.addEdge(e);
  *graph = std::move(loaded);
  if (options) *options = loaded_options;
  return "";
}

std::string saveScanAnchors(const std::string& path, const std::vector<ScanAnchor>& anchors) {
  Writer w(path);
  if (!w.ok()) return path + ": cannot write";
  w.comment(
      "ekf_slam scan anchors: SCAN stamp node x y theta (ekf_slam_core/pose_graph/graph_io.h)");
  for (const ScanAnchor& a : anchors) {
    w.word("SCAN").number(a.stamp).integer(a.node).pose(a.offset).end();
  }
  return w.finish(path);
}

std::string loadScanAnchors(const std::string& path, std::vector<ScanAnchor>* anchors) {
  std::vector<ScanAnchor> loaded;
  const std::string error = readRecords(path, [&](const std::string& keyword, Fields& f) {
    if (keyword != "SCAN") return "unknown record " + keyword;
    ScanAnchor a;
    a.stamp = f.number();
    a.node = static_cast<int>(f.integer());
    a.offset = f.pose();
    if (!f.ok()) return std::string("bad SCAN");
    loaded.push_back(a);
    return std::string();
  });
  if (!error.empty()) return error;
  *anchors = std::move(loaded);
  return "";
}

std::vector<StampedPose> anchoredScanPoses(const std::vector<ScanAnchor>& anchors,
                                           const std::vector<Pose2>& node_poses) {
  std::vector<StampedPose> out;
  out.reserve(anchors.size());
  for (const ScanAnchor& a : anchors) {
    const bool anchored = a.node >= 0 && a.node < static_cast<int>(node_poses.size());
    out.push_back({a.stamp, anchored ? compose(node_poses[a.node], a.offset) : a.offset});
  }
  return out;
}

}  // namespace ekf_slam
