#include "ekf_slam_core/pipeline/slam_state.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <unordered_set>

#include "ekf_slam_core/io/atomic_file.h"

namespace ekf_slam {
namespace {

constexpr char kMagic[] = "EKF-SLAM state\n";
constexpr size_t kMagicSize = sizeof(kMagic) - 1;
constexpr size_t kHeaderSize = kMagicSize + 4 + 8;  // magic, version, payload length
constexpr size_t kChecksumSize = 8;

uint64_t fnv1a(const char* data, size_t size) {
  uint64_t hash = 14695981039346656037ULL;
  for (size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 1099511628211ULL;
  }
  return hash;
}

void putUnsigned(uint64_t value, int bytes, std::string* out) {
  for (int i = 0; i < bytes; ++i) out->push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
}

uint64_t getUnsigned(const char* data, int bytes) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) {
    value |= static_cast<uint64_t>(static_cast<unsigned char>(data[i])) << (8 * i);
  }
  return value;
}

// The payload is written and read by one description of the state
// (describe() below) over one of these two archives, so that the reader
// cannot drift from the writer.
class Writer {
 public:
  static constexpr bool kReading = false;
  uint32_t version() const { return kSlamStateVersion; }
  void item(double& v) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof(bits));
    putUnsigned(bits, 8, &bytes_);
  }
  void item(long& v) { putUnsigned(static_cast<uint64_t>(static_cast<int64_t>(v)), 8, &bytes_); }
  void item(int& v) { putUnsigned(static_cast<uint64_t>(static_cast<int64_t>(v)), 8, &bytes_); }
  void item(bool& v) { bytes_.push_back(v ? 1 : 0); }
  void item(Pose2& p) {
    item(p.x);
    item(p.y);
    item(p.theta);
  }
  void item(Vector2& p) {
    item(p.x());
    item(p.y());
  }
  void item(std::string& s) {
    putUnsigned(s.size(), 8, &bytes_);
    bytes_ += s;
  }
  // A list's length: written; `min_bytes` is what the reader checks.
  size_t length(size_t n, size_t /*min_bytes*/) {
    putUnsigned(n, 8, &bytes_);
    return n;
  }
  bool ok() const { return true; }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

class Reader {
 public:
  static constexpr bool kReading = true;
  Reader(const char* data, size_t size, uint32_t version)
      : data_(data), size_(size), version_(version) {}
  uint32_t version() const { return version_; }
  void item(double& v) {
    const uint64_t bits = take(8);
    std::memcpy(&v, &bits, sizeof(v));
  }
  void item(long& v) { v = static_cast<long>(static_cast<int64_t>(take(8))); }
  void item(int& v) {
    const int64_t wide = static_cast<int64_t>(take(8));
    if (wide < -2147483647LL || wide > 2147483647LL) fail("an integer out of range");
    v = ok() ? static_cast<int>(wide) : 0;
  }
  void item(bool& v) {
    const uint64_t byte = take(1);
    if (byte > 1) fail("a flag that is neither 0 nor 1");
    v = byte == 1;
  }
  void item(Pose2& p) {
    item(p.x);
    item(p.y);
    item(p.theta);
  }
  void item(Vector2& p) {
    item(p.x());
    item(p.y());
  }
  void item(std::string& s) {
    const size_t n = fits(take(8), 1);
    if (!ok()) return;
    s.assign(data_ + at_, n);
    at_ += n;
  }
  // A list's length, read; refused when the bytes left cannot hold that many
  // elements of `min_bytes` each, so that a corrupt length never allocates.
  size_t length(size_t /*written*/, size_t min_bytes) { return fits(take(8), min_bytes); }
  // `n`, or 0 with the reader failed when the bytes left cannot hold n
  // items of `min_bytes` each.
  size_t fits(size_t n, size_t min_bytes) {
    if (!ok()) return 0;
    if (min_bytes > 0 && n > (size_ - at_) / min_bytes) {
      fail("a list longer than the file");
      return 0;
    }
    return n;
  }
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  bool atEnd() const { return at_ == size_; }
  void fail(const std::string& why) {
    if (error_.empty()) error_ = why + " at byte " + std::to_string(kHeaderSize + at_);
  }

 private:
  uint64_t take(int bytes) {
    if (!ok()) return 0;
    if (size_ - at_ < static_cast<size_t>(bytes)) {
      fail("the state ends early");
      return 0;
    }
    const uint64_t value = getUnsigned(data_ + at_, bytes);
    at_ += bytes;
    return value;
  }

  const char* data_;
  size_t size_;
  uint32_t version_;
  size_t at_ = 0;
  std::string error_;
};

// A list: its length, then each element through `element`.
template <class Archive, class T, class Element>
void list(Archive& a, std::vector<T>& v, size_t min_bytes, Element element) {
  const size_t n = a.length(v.size(), min_bytes);
  if constexpr (Archive::kReading) v.assign(n, T());
  for (size_t i = 0; i < n && a.ok(); ++i) element(v[i]);
}

// A matrix, row by row.
template <class Archive, class Matrix>
void matrix(Archive& a, Matrix& m) {
  for (int i = 0; i < m.rows(); ++i) {
    for (int j = 0; j < m.cols(); ++j) a.item(m(i, j));
  }
}

template <class Archive>
void describe(Archive& a, LoopClosureCounters& c) {
  for (long* v :
       {&c.key_scans, &c.candidates, &c.accepted, &c.refused, &c.refused_by_score,
        &c.refused_by_fit, &c.refused_as_degenerate, &c.ambiguous, &c.dropped, &c.inconsistent,
        &c.unconfirmed, &c.released, &c.heading_loops, &c.optimisations}) {
    a.item(*v);
  }
  a.item(c.optimisation_seconds);
  a.item(c.verification_seconds);
}

template <class Archive>
void describe(Archive& a, PoseGraph& graph) {
  std::vector<Pose2> poses = graph.poses();
  list(a, poses, 24, [&](Pose2& p) { a.item(p); });
  std::vector<PoseGraphEdge> edges = graph.edges();
  list(a, edges, 8 * 14 + 2, [&](PoseGraphEdge& e) {
    a.item(e.from);
    a.item(e.to);
    a.item(e.measurement);
    for (int i = 0; i < 9; ++i) a.item(e.information(i / 3, i % 3));
    a.item(e.robust);
    a.item(e.active);
  });
  if constexpr (Archive::kReading) {
    if (!a.ok()) return;
    graph = PoseGraph();
    for (const Pose2& p : poses) graph.addNode(p);
    for (const PoseGraphEdge& e : edges) {
      if (e.from < 0 || e.to < 0 || e.from >= graph.nodeCount() || e.to >= graph.nodeCount()) {
        a.fail("a graph edge joins a missing node");
        return;
      }
      graph.addEdge(e);
    }
  }
}

template <class Archive>
void describe(Archive& a, LoopCloserState& s) {
  list(a, s.keys, 24 + 8 + 8 * 5, [&](LoopCloserState::Key& k) {
    a.item(k.front_end);
    list(a, k.points, 16, [&](Vector2& p) { a.item(p); });
    a.item(k.travel_from_previous);
    a.item(k.retry_after);
    a.item(k.scan_index);
    a.item(k.stamp);
    a.item(k.wall_direction);
  });
  list(a, s.scans, 8 * 5, [&](LoopCloserState::ScanEntry& e) {
    a.item(e.stamp);
    a.item(e.key);
    a.item(e.offset);
  });
  describe(a, s.graph);
  list(a, s.adjacency, 8, [&](std::vector<std::pair<int, double>>& neighbours) {
    list(a, neighbours, 16, [&](std::pair<int, double>& n) {
      a.item(n.first);
      a.item(n.second);
    });
  });
  list(a, s.heading_edges, 8, [&](int& e) { a.item(e); });
  describe(a, s.counters);
  a.item(s.scan_count);
  a.item(s.next_attempt);
  a.item(s.heading_loops_since_optimisation);
  a.item(s.has_hypothesis);
  a.item(s.hypothesis_from);
  a.item(s.hypothesis_to);
  a.item(s.hypothesis_relative);
}

template <class Archive>
void describe(Archive& a, BackEndLinkState& s) {
  describe(a, s.closer);
  list(a, s.key_filtered, 24, [&](Pose2& p) { a.item(p); });
  list(a, s.landmark_scan, 16, [&](std::pair<int, int>& l) {
    a.item(l.first);
    a.item(l.second);
  });
  a.item(s.has_map_from_graph);
  a.item(s.map_from_graph);
  a.item(s.last_front_end);
  list(a, s.record_of_loop_scan, 8, [&](long& r) { a.item(r); });
}

template <class Archive>
void describe(Archive& a, ScanHistoryState& h) {
  list(a, h.records, 8 * 23, [&](ScanRecord& r) {
    a.item(r.stamp);
    a.item(r.filtered);
    matrix(a, r.covariance);
    a.item(r.odometry);
    a.item(r.iteration);
    a.item(r.odometry_at_iteration);
    a.item(r.causal);
  });
  a.item(h.first_record);
  a.item(h.first_iteration);
  list(a, h.steps, 8 * 34, [&](SmootherStep& step) {
    a.item(step.stamp);
    a.item(step.filtered);
    matrix(a, step.filtered_cov);
    matrix(a, step.F_next);
    a.item(step.predicted_next);
    matrix(a, step.predicted_next_cov);
  });
  list(a, h.iterations, 8 * 23 + 2, [&](SmootherIteration& it) {
    a.item(it.stamp);
    a.item(it.filtered);
    a.item(it.has_control);
    a.item(it.control.rot1);
    a.item(it.control.trans);
    a.item(it.control.rot2);
    matrix(a, it.control_covariance);
    a.item(it.motion);
    a.item(it.has_wheels);
    a.item(it.wheels);
    list(a, it.sightings, 8 * 7, [&](LandmarkSighting& sighting) {
      a.item(sighting.landmark_id);
      a.item(sighting.observation.z.range);
      a.item(sighting.observation.z.bearing);
      matrix(a, sighting.observation.covariance);
    });
  });
  list(a, h.merged_into, 16, [&](std::pair<int, int>& m) {
    a.item(m.first);
    a.item(m.second);
  });
  list(a, h.last_estimates, 24, [&](std::pair<int, Vector2>& e) {
    a.item(e.first);
    a.item(e.second);
  });
  a.item(h.prior_mean);
  matrix(a, h.prior_covariance);
}

// The filter: the live mean, the covariance's lower triangle (the stored
// one, which is current; the upper one is filled on reading) and the
// landmarks' bookkeeping.
template <class Archive>
void describe(Archive& a, FilterState& f) {
  int dim = f.dim;
  a.item(dim);
  if constexpr (Archive::kReading) {
    if (!a.ok()) return;
    // The mean and the triangle must fit in the bytes left.
    const size_t entries = dim < 3 ? 0 : static_cast<size_t>(dim) * (dim + 3) / 2;
    if (dim < FilterState::kPoseDim || a.fits(entries, 8) != entries) {
      a.fail("a filter state of impossible size " + std::to_string(dim));
      return;
    }
    f = FilterState();
    f.reserve(dim);
    f.dim = dim;
  }
  for (int i = 0; i < dim && a.ok(); ++i) a.item(f.x(i));
  for (int i = 0; i < dim && a.ok(); ++i) {
    for (int j = 0; j <= i; ++j) {
      a.item(f.P(i, j));
      if constexpr (Archive::kReading) f.P(j, i) = f.P(i, j);
    }
  }
  list(a, f.landmarks, 8 * 6 + 16, [&](LandmarkInfo& l) {
    a.item(l.id);
    int kind = static_cast<int>(l.kind);
    a.item(kind);
    if (kind < 0 || kind > static_cast<int>(LandmarkKind::kLineAngle)) {
      if constexpr (Archive::kReading) a.fail("a landmark of unknown kind");
      kind = 0;
    }
    l.kind = static_cast<LandmarkKind>(kind);
    a.item(l.index);
    a.item(l.observations);
    a.item(l.created_step);
    a.item(l.last_seen_step);
    a.item(l.first_estimate);
  });
  if constexpr (Archive::kReading) {
    for (int slot = 0; slot < f.landmarkCount(); ++slot) f.slot_of_id[f.landmarks[slot].id] = slot;
  }
  a.item(f.next_id);
  a.item(f.step);
  for (int i = 0; i < 9; ++i) a.item(f.last_F(i / 3, i % 3));
  a.item(f.have_prior_position);
  a.item(f.prior_position);
  a.item(f.mapping_enabled);
}

template <class Archive>
void describe(Archive& a, SlamState& s) {
  a.item(s.configuration);
  a.item(s.laser_pose);
  describe(a, s.filter);
  std::vector<std::pair<int, LineSupport>> support(s.line_support.begin(), s.line_support.end());
  std::sort(support.begin(), support.end(),
            [](const auto& l, const auto& r) { return l.first < r.first; });
  list(a, support, 8 * 5, [&](std::pair<int, LineSupport>& l) {
    a.item(l.first);
    a.item(l.second.s_min);
    a.item(l.second.s_max);
    a.item(l.second.endpoint_ids[0]);
    a.item(l.second.endpoint_ids[1]);
  });
  if constexpr (Archive::kReading) {
    s.line_support = std::unordered_map<int, LineSupport>(support.begin(), support.end());
  }
  describe(a, s.back_end);
  a.item(s.has_front_end);
  a.item(s.front_end.last_raw);
  a.item(s.front_end.last_corrected);
  a.item(s.front_end.last_key_pose);
  a.item(s.front_end.last_stamp);
  list(a, s.front_end.map_points, 16, [&](Vector2& p) { a.item(p); });
  list(a, s.front_end.map_normals, 16, [&](Vector2& p) { a.item(p); });
  a.item(s.scans);
  a.item(s.has_last_iteration);
  a.item(s.last_stamp);
  a.item(s.last_raw_odometry);
  describe(a, s.history);
  // What later versions added comes last.
  if (a.version() >= 4) {
    list(a, s.back_end.point_seen_at, 24, [&](std::pair<int, Vector2>& l) {
      a.item(l.first);
      a.item(l.second);
    });
  }
}

// What decoding cannot see field by field: the landmarks' layout in the
// state, unique ids, finite numbers, the link's lists against the closer's.
std::string inconsistency(const SlamState& s) {
  const FilterState& f = s.filter;
  int index = FilterState::kPoseDim;
  std::unordered_set<int> ids;
  for (const LandmarkInfo& l : f.landmarks) {
    if (l.index != index) return "the landmarks' positions in the filter state do not follow";
    if (l.id < 0 || l.id >= f.next_id || !ids.insert(l.id).second ||
        f.slot_of_id.size() != f.landmarks.size()) {
      return "landmark id " + std::to_string(l.id) + " is repeated or beyond the next id";
    }
    index += landmarkDim(l.kind);
  }
  if (index != f.dim) return "the landmarks do not fill the filter state";
  if (!f.x.head(f.dim).allFinite() || !f.P.topLeftCorner(f.dim, f.dim).allFinite()) {
    return "the filter state holds a number that is not finite";
  }
  const BackEndLinkState& b = s.back_end;
  if (b.key_filtered.size() != b.closer.keys.size()) {
    return "the filter's poses at the key scans do not match the key scans";
  }
  if (b.record_of_loop_scan.size() > static_cast<size_t>(b.closer.scan_count)) {
    return "the history records of the loop scans outnumber the loop scans";
  }
  const ScanHistoryState& h = s.history;
  if (h.steps.size() != h.iterations.size()) {
    return "the history's two records of the iterations differ in length";
  }
  return "";
}

}  // namespace

std::string encodeSlamState(const SlamState& state) {
  Writer writer;
  SlamState copy = state;  // describe() takes its fields by reference
  describe(writer, copy);
  const std::string& payload = writer.bytes();
  std::string out(kMagic, kMagicSize);
  putUnsigned(kSlamStateVersion, 4, &out);
  putUnsigned(payload.size(), 8, &out);
  out += payload;
  putUnsigned(fnv1a(payload.data(), payload.size()), 8, &out);
  return out;
}

std::string decodeSlamState(const std::string& bytes, SlamState* state) {
  if (bytes.size() < kMagicSize || bytes.compare(0, kMagicSize, kMagic) != 0) {
    return "not a SLAM state file (it does not start with \"EKF-SLAM state\")";
  }
  if (bytes.size() < kHeaderSize) return "the state ends inside its header";
  const uint32_t version = static_cast<uint32_t>(getUnsigned(bytes.data() + kMagicSize, 4));
  if (version < kOldestSlamStateVersion || version > kSlamStateVersion) {
    return "state format version " + std::to_string(version) + "; this build reads versions " +
           std::to_string(kOldestSlamStateVersion) + " to " + std::to_string(kSlamStateVersion) +
           (version < kOldestSlamStateVersion
                ? " (an older state holds no history of the scans: map the log again)"
                : "");
  }
  const uint64_t length = getUnsigned(bytes.data() + kMagicSize + 4, 8);
  if (length > bytes.size() - kHeaderSize || bytes.size() - kHeaderSize - length != kChecksumSize) {
    return "the state is " + std::to_string(bytes.size()) + " bytes, its header announces " +
           std::to_string(kHeaderSize + length + kChecksumSize) + " (truncated or extended)";
  }
  const char* payload = bytes.data() + kHeaderSize;
  if (fnv1a(payload, length) != getUnsigned(payload + length, 8)) {
    return "the state's checksum does not match its content (the file is corrupt)";
  }
  Reader reader(payload, length, version);
  SlamState read;
  describe(reader, read);
  if (reader.ok() && !reader.atEnd()) reader.fail("bytes after the state's last field");
  if (!reader.ok()) return reader.error();
  if (const std::string problem = inconsistency(read); !problem.empty()) return problem;
  *state = std::move(read);
  return "";
}

std::string writeSlamState(const std::string& path, const SlamState& state) {
  return writeFileAtomically(path, encodeSlamState(state));
}

std::string readSlamState(const std::string& path, SlamState* state) {
  std::string bytes;
  if (!readWholeFile(path, &bytes)) return path + ": cannot be read";
  const std::string problem = decodeSlamState(bytes, state);
  return problem.empty() ? "" : path + ": " + problem;
}

}  // namespace ekf_slam
