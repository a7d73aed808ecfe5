#include "ekf_slam_core/mecp/empty_convex_polygon.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {
namespace {

double cross(const Vector2& a, const Vector2& b) { return a.x() * b.y() - a.y() * b.x(); }

// > 0 when c is strictly left of the directed line a → b.
double orientation(const Vector2& a, const Vector2& b, const Vector2& c) {
  return cross(b - a, c - a);
}

// A polygon's merit: more vertices first, then more area.
struct Score {
  int vertices = 0;         // 0: no polygon
  double twice_area = 0.0;  // m²
};

bool better(const Score& a, const Score& b) {
  return a.vertices != b.vertices ? a.vertices > b.vertices : a.twice_area > b.twice_area;
}

// Whether b comes after a in the order (y, then x): the points a polygon
// whose lowest vertex is a may use as its other vertices.
bool after(const Vector2& a, const Vector2& b) {
  return b.y() > a.y() || (b.y() == a.y() && b.x() > a.x());
}

// The fan dynamic programme of the header for one anchor (the polygon's
// lowest vertex). Candidates are numbered 0 … m−1 by angle around the
// anchor, then by distance; candidates on one ray from the anchor share a
// `ray` number and occupy [ray_begin, ray_end).
class AnchoredSolver {
 public:
  AnchoredSolver(const std::vector<Vector2>& points, int anchor, const Vector2& query)
      : anchor_(points[anchor]), query_(query) {
    for (int i = 0; i < static_cast<int>(points.size()); ++i) {
      if (after(anchor_, points[i])) index_.push_back(i);
    }
    m_ = static_cast<int>(index_.size());
    std::vector<double> angle(points.size());
    for (int i : index_) {
      const Vector2 d = points[i] - anchor_;
      angle[i] = std::atan2(d.y(), d.x());  // [0, π): every candidate is above the anchor
    }
    std::sort(index_.begin(), index_.end(), [&](int i, int j) { return angle[i] < angle[j]; });
    for (int i : index_) v_.push_back(points[i]);
    // Group the rays exactly (atan2 may round collinear points apart), then
    // order each ray by distance.
    ray_begin_.assign(m_, 0);
    ray_end_.assign(m_, m_);
    for (int begin = 0; begin < m_;) {
      int end = begin + 1;
      while (end < m_ && cross(v_[begin] - anchor_, v_[end] - anchor_) == 0.0) ++end;
      std::vector<int> ray(end - begin);
      for (int t = begin; t < end; ++t) ray[t - begin] = t;
      std::sort(ray.begin(), ray.end(), [&](int s, int t) {
        return (v_[s] - anchor_).squaredNorm() < (v_[t] - anchor_).squaredNorm();
      });
      std::vector<Vector2> v(end - begin);
      std::vector<int> index(end - begin);
      for (int t = 0; t < end - begin; ++t) {
        v[t] = v_[ray[t]];
        index[t] = index_[ray[t]];
      }
      for (int t = begin; t < end; ++t) {
        v_[t] = v[t - begin];
        index_[t] = index[t - begin];
        ray_begin_[t] = begin;
        ray_end_[t] = end;
      }
      begin = end;
    }
  }

  // The best polygon of this anchor, whose input index is `anchor_index`;
  // its vertices (input indices, counter-clockwise, the anchor first) in
  // `*vertices`.
  Score solve(int anchor_index, std::vector<int>* vertices) {
    if (m_ < 2) return {};
    computeEmptyTriangles();
    score_.assign(m_ * m_, Score());
    predecessor_.assign(m_ * m_, -1);
    // Triangles (anchor, i, k): the shortest chains.
    for (int i = 0; i < m_; ++i) {
      if (!edgeHoldsQuery(anchor_, v_[i])) continue;
      for (int k = ray_end_[i]; k < m_; ++k) {
        if (emptyTriangle(i, k) && edgeHoldsQuery(v_[i], v_[k])) {
          at(score_, i, k) = {3, cross(v_[i] - anchor_, v_[k] - anchor_)};
        }
      }
    }
    for (int j = 0; j < m_; ++j) extendThrough(j);
    // Close every chain (…, i, j) with the edge j → anchor.
    Score best;
    int best_i = -1, best_j = -1;
    for (int j = 0; j < m_; ++j) {
      if (!edgeHoldsQuery(v_[j], anchor_)) continue;
      for (int i = 0; i < ray_begin_[j]; ++i) {
        if (better(at(score_, i, j), best)) {
          best = at(score_, i, j);
          best_i = i;
          best_j = j;
        }
      }
    }
    if (best.vertices == 0) return {};
    std::vector<int> chain{best_j};
    for (int i = best_i, j = best_j;;) {
      chain.push_back(i);
      const int h = at(predecessor_, i, j);
      if (h < 0) break;
      j = i;
      i = h;
    }
    vertices->assign(1, anchor_index);
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) vertices->push_back(index_[*it]);
    return best;
  }

 private:
  template <class T>
  T& at(std::vector<T>& table, int i, int j) {
    return table[i * m_ + j];
  }
  bool emptyTriangle(int j, int k) const { return empty_[j * m_ + k]; }

  bool edgeHoldsQuery(const Vector2& from, const Vector2& to) const {
    return orientation(from, to, query_) > 0.0;
  }

  // No candidate strictly closer on v_j's ray: a–v_j may be an inner diagonal.
  bool diagonalClear(int j) const {
    return (v_[ray_begin_[j]] - anchor_).squaredNorm() == (v_[j] - anchor_).squaredNorm();
  }

  // empty_(j, k), k on a later ray: no candidate strictly inside the
  // triangle (anchor, v_j, v_k). Those strictly inside lie on rays strictly
  // between and strictly left of v_j → v_k; seen from v_j all such
  // directions lie left of the ray anchor → v_j, a half-plane, so comparing
  // against the one furthest counter-clockwise decides.
  void computeEmptyTriangles() {
    empty_.assign(m_ * m_, 0);
    for (int j = 0; j < m_; ++j) {
      int furthest = -1;
      for (int begin = ray_end_[j]; begin < m_; begin = ray_end_[begin]) {
        const int end = ray_end_[begin];
        for (int k = begin; k < end; ++k) {
          empty_[j * m_ + k] =
              furthest < 0 || cross(v_[k] - v_[j], v_[furthest] - v_[j]) <= 0.0 ? 1 : 0;
        }
        for (int k = begin; k < end; ++k) {
          if (furthest < 0 || cross(v_[furthest] - v_[j], v_[k] - v_[j]) > 0.0) furthest = k;
        }
      }
    }
  }

  // Extends every chain ending in an edge (i, j) by an edge (j, k).
  void extendThrough(int j) {
    if (!diagonalClear(j)) return;
    std::vector<int> incoming, outgoing;
    for (int i = 0; i < ray_begin_[j]; ++i) {
      if (at(score_, i, j).vertices > 0) incoming.push_back(i);
    }
    for (int k = ray_end_[j]; k < m_; ++k) {
      if (emptyTriangle(j, k) && edgeHoldsQuery(v_[j], v_[k])) outgoing.push_back(k);
    }
    if (incoming.empty() || outgoing.empty()) return;
    // Directions of v_i → v_j and v_j → v_k all lie left of the ray anchor
    // → v_j; order them by angle from that ray.
    const Vector2 axis = v_[j] - anchor_;
    const auto angle_from_axis = [&axis](const Vector2& d) {
      return std::atan2(cross(axis, d), axis.dot(d));
    };
    std::vector<double> key(m_);
    for (int i : incoming) key[i] = angle_from_axis(v_[j] - v_[i]);
    for (int k : outgoing) key[k] = angle_from_axis(v_[k] - v_[j]);
    const auto by_key = [&key](int s, int t) { return key[s] < key[t]; };
    std::sort(incoming.begin(), incoming.end(), by_key);
    std::sort(outgoing.begin(), outgoing.end(), by_key);
    // v_i → v_j → v_k turns strictly left iff v_k − v_j is strictly
    // counter-clockwise of v_j − v_i: a prefix of `incoming` that grows with k.
    Score running;
    int running_i = -1;
    std::size_t next = 0;
    for (int k : outgoing) {
      while (next < incoming.size() && cross(v_[j] - v_[incoming[next]], v_[k] - v_[j]) > 0.0) {
        const int i = incoming[next++];
        if (better(at(score_, i, j), running)) {
          running = at(score_, i, j);
          running_i = i;
        }
      }
      if (running_i < 0) continue;
      const Score extended{running.vertices + 1, running.twice_area + cross(axis, v_[k] - anchor_)};
      if (better(extended, at(score_, j, k))) {
        at(score_, j, k) = extended;
        at(predecessor_, j, k) = running_i;
      }
    }
  }

  Vector2 anchor_;
  Vector2 query_;
  int m_ = 0;
  std::vector<int> index_;  // input index of each candidate
  std::vector<Vector2> v_;  // candidate positions
  std::vector<int> ray_begin_, ray_end_;
  std::vector<char> empty_;       // m × m, see computeEmptyTriangles
  std::vector<Score> score_;      // m × m: best chain anchor → … → v_i → v_j
  std::vector<int> predecessor_;  // m × m: the vertex before v_i in it, −1: v_i is the first
};

}  // namespace

std::vector<int> maximumEmptyConvexPolygon(const std::vector<Vector2>& points,
                                           const Vector2& query) {
  if (points.size() < 3 || !query.allFinite()) return {};
  for (const Vector2& p : points) {
    if (!p.allFinite()) return {};
  }
  Score best;
  std::vector<int> best_vertices, vertices;
  for (int anchor = 0; anchor < static_cast<int>(points.size()); ++anchor) {
    AnchoredSolver solver(points, anchor, query);
    const Score score = solver.solve(anchor, &vertices);
    if (better(score, best)) {
      best = score;
      best_vertices = vertices;
    }
  }
  return best_vertices;
}

double polygonArea(const std::vector<Vector2>& points, const std::vector<int>& vertices) {
  double twice_area = 0.0;
  for (std::size_t t = 0; t < vertices.size(); ++t) {
    twice_area += cross(points[vertices[t]], points[vertices[(t + 1) % vertices.size()]]);
  }
  return 0.5 * twice_area;
}

}  // namespace ekf_slam
