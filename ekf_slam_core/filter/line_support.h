// What the filter's state does not hold about a line landmark but a map
// needs: the stretch of the infinite line that was actually seen, and, for
// a θ-only landmark, the point landmarks that fix its offset.
//
// The extent is measured along the line's direction d = (−sin θ, cos θ)
// from its foot point p·(cos θ, sin θ), in the map frame; it grows as the
// line's observed segments are matched to it. The pipeline keeps one per
// line landmark id; markers and map files draw the segment from it.
#pragma once

namespace ekf_slam {

struct LineSupport {
  double s_min = 0.0;  // m, along d from the foot point
  double s_max = 0.0;  // m, s_min <= s_max
  // kLineAngle: the point landmarks on the line (thesis §4.3.3: its
  // endpoints), -1 where there is none.
  int endpoint_ids[2] = {-1, -1};
};

}  // namespace ekf_slam
