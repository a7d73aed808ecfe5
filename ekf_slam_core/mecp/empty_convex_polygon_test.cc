// The maximum empty convex polygon against a brute-force enumeration of
// every subset, on random real and lattice (collinear-rich) point sets.
#include "ekf_slam_core/mecp/empty_convex_polygon.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace ekf_slam {
namespace {

double cross(const Vector2& a, const Vector2& b) { return a.x() * b.y() - a.y() * b.x(); }

bool strictlyInside(const std::vector<Vector2>& polygon, const Vector2& x) {
  for (std::size_t t = 0; t < polygon.size(); ++t) {
    const Vector2& a = polygon[t];
    const Vector2& b = polygon[(t + 1) % polygon.size()];
    if (!(cross(b - a, x - a) > 0.0)) return false;
  }
  return true;
}

// Strictly convex hull, counter-clockwise (Andrew's monotone chain, collinear
// points dropped).
std::vector<Vector2> strictHull(std::vector<Vector2> p) {
  std::sort(p.begin(), p.end(), [](const Vector2& a, const Vector2& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  });
  std::vector<Vector2> hull(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 1] - hull[k - 2], p[i] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 1] - hull[k - 2], p[i] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k - 1);
  return hull;
}

struct Best {
  int vertices = 0;
  double area = 0.0;
};

// Every subset of at least three points in strictly convex position, with
// `query` strictly inside and no input point strictly inside.
Best bruteForce(const std::vector<Vector2>& points, const Vector2& query) {
  const int n = static_cast<int>(points.size());
  Best best;
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    std::vector<Vector2> subset;
    for (int i = 0; i < n; ++i) {
      if (mask & (1u << i)) subset.push_back(points[i]);
    }
    if (subset.size() < 3) continue;
    const std::vector<Vector2> hull = strictHull(subset);
    if (hull.size() != subset.size()) continue;  // a point inside, on an edge, or doubled
    if (!strictlyInside(hull, query)) continue;
    bool empty = true;
    for (int i = 0; i < n && empty; ++i) empty = !strictlyInside(hull, points[i]);
    if (!empty) continue;
    double twice_area = 0.0;
    for (std::size_t t = 0; t < hull.size(); ++t) {
      twice_area += cross(hull[t], hull[(t + 1) % hull.size()]);
    }
    const int size = static_cast<int>(hull.size());
    if (size > best.vertices || (size == best.vertices && 0.5 * twice_area > best.area)) {
      best = {size, 0.5 * twice_area};
    }
  }
  return best;
}

// The returned polygon is what the header promises, whatever its size.
::testing::AssertionResult isEmptyConvexAroundQuery(const std::vector<Vector2>& points,
                                                    const std::vector<int>& vertices,
                                                    const Vector2& query) {
  if (vertices.empty()) return ::testing::AssertionSuccess();
  std::vector<Vector2> polygon;
  for (int i : vertices) polygon.push_back(points[i]);
  const std::size_t k = polygon.size();
  if (k < 3) return ::testing::AssertionFailure() << k << " vertices";
  for (std::size_t t = 0; t < k; ++t) {
    const Vector2& a = polygon[t];
    const Vector2& b = polygon[(t + 1) % k];
    const Vector2& c = polygon[(t + 2) % k];
    if (!(cross(b - a, c - b) > 0.0)) {
      return ::testing::AssertionFailure() << "not a strict left turn at vertex " << (t + 1) % k;
    }
  }
  if (!strictlyInside(polygon, query)) return ::testing::AssertionFailure() << "query outside";
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (strictlyInside(polygon, points[i])) {
      return ::testing::AssertionFailure() << "point " << i << " inside";
    }
  }
  // A polygon winding more than once would pass the left-turn test.
  double turning = 0.0;
  for (std::size_t t = 0; t < k; ++t) {
    const Vector2 d0 = polygon[(t + 1) % k] - polygon[t];
    const Vector2 d1 = polygon[(t + 2) % k] - polygon[(t + 1) % k];
    turning += std::atan2(cross(d0, d1), d0.dot(d1));
  }
  if (std::abs(turning - 2.0 * kPi) > 1e-9) {
    return ::testing::AssertionFailure() << "turns " << turning << " rad";
  }
  return ::testing::AssertionSuccess();
}

void expectMatchesBruteForce(const std::vector<Vector2>& points, const Vector2& query,
                             const std::string& label) {
  const std::vector<int> vertices = maximumEmptyConvexPolygon(points, query);
  const Best expected = bruteForce(points, query);
  EXPECT_TRUE(isEmptyConvexAroundQuery(points, vertices, query)) << label;
  ASSERT_EQ(static_cast<int>(vertices.size()), expected.vertices) << label;
  if (!vertices.empty()) {
    EXPECT_NEAR(polygonArea(points, vertices), expected.area, 1e-9 * (1.0 + expected.area))
        << label;
  }
}

TEST(MaximumEmptyConvexPolygon, MatchesBruteForceOnRandomRealPoints) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-3.0, 3.0);
  std::uniform_int_distribution<int> count(3, 9);
  int found = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    std::vector<Vector2> points(count(rng));
    for (Vector2& p : points) p = Vector2(coordinate(rng), coordinate(rng));
    const Vector2 query(0.5 * coordinate(rng), 0.5 * coordinate(rng));
    expectMatchesBruteForce(points, query, "trial " + std::to_string(trial));
    if (HasFatalFailure()) return;
    found += maximumEmptyConvexPolygon(points, query).empty() ? 0 : 1;
  }
  // Both outcomes occur: the comparison covers polygons and their absence.
  EXPECT_GT(found, 500);
  EXPECT_LT(found, 1500);
}

TEST(MaximumEmptyConvexPolygon, MatchesBruteForceOnLatticePointsWithCollinearities) {
  // Small integer coordinates: collinear triples, points on edges and on
  // inner diagonals, repeated points, a query on an edge or on a point. All
  // cross products are exact.
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> coordinate(0, 4);
  std::uniform_int_distribution<int> count(3, 9);
  std::uniform_int_distribution<int> query_kind(0, 2);
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<Vector2> points(count(rng));
    for (Vector2& p : points) p = Vector2(coordinate(rng), coordinate(rng));
    // Queries on lattice points, on midpoints between two of them, or off
    // the lattice.
    const int kind = query_kind(rng);
    Vector2 query(coordinate(rng), coordinate(rng));
    if (kind == 1) query = 0.5 * (query + Vector2(coordinate(rng), coordinate(rng)));
    if (kind == 2) query += Vector2(0.1234, 0.2345);
    expectMatchesBruteForce(points, query, "lattice trial " + std::to_string(trial));
    if (HasFatalFailure()) return;
  }
}

TEST(MaximumEmptyConvexPolygon, RoomCornersAroundTheRobotAreOnePolygon) {
  // Six corners of a hexagonal room, the robot in the middle, a pillar's
  // corner off to one side inside the room.
  std::vector<Vector2> points;
  for (int t = 0; t < 6; ++t) {
    points.emplace_back(3.0 * std::cos(t * kPi / 3.0), 3.0 * std::sin(t * kPi / 3.0));
  }
  points.emplace_back(2.0, 0.5);
  const std::vector<int> vertices = maximumEmptyConvexPolygon(points, Vector2(-0.5, 0.1));
  EXPECT_TRUE(isEmptyConvexAroundQuery(points, vertices, Vector2(-0.5, 0.1)));
  // The pillar corner is inside the hexagon, so it must be a vertex: the
  // hexagon with one vertex swapped for the pillar corner.
  ASSERT_EQ(vertices.size(), 6u);
  EXPECT_NE(std::find(vertices.begin(), vertices.end(), 6), vertices.end());
  // Counter-clockwise from the lowest vertex.
  EXPECT_GT(polygonArea(points, vertices), 0.0);
  for (int i : vertices) EXPECT_GE(points[i].y(), points[vertices[0]].y());
}

TEST(MaximumEmptyConvexPolygon, NoPolygonForDegenerateInput) {
  const std::vector<Vector2> square{{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  EXPECT_EQ(maximumEmptyConvexPolygon(square, Vector2(1, 1)).size(), 4u);
  // Fewer than three points, collinear points, the query outside or on the
  // boundary, non-finite input.
  EXPECT_TRUE(maximumEmptyConvexPolygon({{0, 0}, {1, 0}}, Vector2(0.5, 0.1)).empty());
  EXPECT_TRUE(maximumEmptyConvexPolygon({{0, 0}, {1, 1}, {2, 2}, {3, 3}}, Vector2(1, 1.5)).empty());
  EXPECT_TRUE(maximumEmptyConvexPolygon(square, Vector2(3, 1)).empty());
  EXPECT_TRUE(maximumEmptyConvexPolygon(square, Vector2(2, 1)).empty());
  EXPECT_TRUE(maximumEmptyConvexPolygon(square, Vector2(1, 0)).empty());
  std::vector<Vector2> with_nan = square;
  with_nan.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0.0);
  EXPECT_TRUE(maximumEmptyConvexPolygon(with_nan, Vector2(1, 1)).empty());
  EXPECT_TRUE(maximumEmptyConvexPolygon(square, Vector2(std::numeric_limits<double>::infinity(), 1))
                  .empty());
  // The query on a point: no empty polygon has it strictly inside.
  std::vector<Vector2> centred = square;
  centred.emplace_back(1, 1);
  EXPECT_TRUE(maximumEmptyConvexPolygon(centred, Vector2(1, 1)).empty());
}

TEST(MaximumEmptyConvexPolygon, SixtyPointsStayValid) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> coordinate(-5.0, 5.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vector2> points(60);
    for (Vector2& p : points) p = Vector2(coordinate(rng), coordinate(rng));
    const Vector2 query(0.3 * coordinate(rng), 0.3 * coordinate(rng));
    const std::vector<int> vertices = maximumEmptyConvexPolygon(points, query);
    EXPECT_TRUE(isEmptyConvexAroundQuery(points, vertices, query)) << trial;
  }
}

}  // namespace
}  // namespace ekf_slam
