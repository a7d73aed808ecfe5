// The maximum empty convex polygon (MECP) around the robot (thesis §4.4.2).
//
// Given points P = {p_0 … p_{n−1}} (the current point features) and a query
// point q (the robot), find a polygon whose
//   - vertices are points of P in strictly convex position (no three
//     consecutive vertices collinear),
//   - interior holds no point of P (points on its edges are allowed),
//   - interior holds q (strictly: q on an edge does not count),
// with the most vertices; among those, the one with the largest area.
//
// Method (a dynamic programme over fans, after Avis & Rappaport 1985 and
// Dobkin, Edelsbrunner & Overmars 1990). Every convex polygon has a unique
// lowest vertex a (smallest y, then smallest x). Fix a; the other vertices
// v_1 … v_m lie above a and, in counter-clockwise order, have strictly
// increasing angle around a. The polygon is the fan of triangles
// (a, v_i, v_{i+1}), so
//   - it is empty iff every fan triangle has an empty interior and no point
//     lies on an inner diagonal a–v_i (1 < i < m), the only parts of the
//     polygon's interior the triangles' interiors miss;
//   - it holds q strictly iff q is strictly left of every directed edge
//     (a→v_1, v_i→v_{i+1}, v_m→a), a condition on single edges;
//   - it is convex iff the turn v_{i−1}→v_i→v_{i+1} is strictly left at
//     every inner v_i (the turns at a, v_1 and v_m are left by the angular
//     order).
// The state is the last edge (v_{i−1}, v_i); its value, (vertex count,
// twice the area), adds up triangle by triangle and is compared
// lexicographically, which addition preserves, so the best chain into an
// edge extends to the best polygon. For each v_i the incoming edges are
// sorted by direction and the admissible predecessors of an outgoing edge
// form a prefix (all directions lie in the half-plane left of the ray
// a→v_i), so one sweep with a running maximum serves every outgoing edge.
// Triangle emptiness for a fixed v_i is one sweep over the later rays,
// keeping the intermediate point seen furthest counter-clockwise from v_i.
//
// Cost: O(n² log n) per anchor, O(n³ log n) in all, O(n²) memory.
//
// Predicates are exact for inputs whose cross products are exact (integer
// coordinates of moderate size); for general doubles, near-degenerate
// triples (collinear to rounding) may be classified either way.
#pragma once

#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

// Indices into `points` of the maximum empty convex polygon strictly
// containing `query`, counter-clockwise from its lowest vertex. Empty when
// there is none: fewer than three points, all collinear, `query` outside
// every empty convex polygon, or any coordinate non-finite. Coincident
// points: only one of them can be a vertex; the others lie on that vertex,
// not inside.
std::vector<int> maximumEmptyConvexPolygon(const std::vector<Vector2>& points,
                                           const Vector2& query);

// Area (m²) of the polygon through `points[vertices]` in the given order
// (shoelace formula): positive when counter-clockwise.
double polygonArea(const std::vector<Vector2>& points, const std::vector<int>& vertices);

}  // namespace ekf_slam
