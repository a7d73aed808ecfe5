#include "ekf_slam_core/pipeline/loop_closed_map.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace ekf_slam {
namespace {

// Along a line whose normal points at `theta` (line_landmarks.cc's convention).
Vector2 along(double theta) { return Vector2(-std::sin(theta), std::cos(theta)); }

}  // namespace

LoopClosedMap loopClosedMap(const SlamPipeline& pipeline, const Pose2& causal) {
  const EkfSlam& filter = pipeline.filter();
  LoopClosedMap out{filter, pipeline.lineSupport()};
  const std::vector<std::pair<int, Pose2>> corrections =
      pipeline.backEnd().landmarkCorrections(filter);
  out.filter.reanchor(compose(causal, inverse(filter.pose())), corrections);
  // A (p, θ) line's extent is measured along it from its foot point, which
  // moves with the line: the extent's ends move with the correction and are
  // measured again along the moved line (whose normal may have turned round
  // to keep p >= 0).
  for (const auto& [id, correction] : corrections) {
    const auto seen = out.support.find(id);
    const int slot = filter.slotOf(id);
    if (seen == out.support.end() || slot < 0 || filter.landmarkKind(slot) != LandmarkKind::kLine) {
      continue;
    }
    const PolarLine before = filter.lineLandmark(slot);
    const Vector2 foot = before.p * Vector2(std::cos(before.theta), std::sin(before.theta));
    const Vector2 first =
        transformFrom(correction, foot + seen->second.s_min * along(before.theta));
    const Vector2 last = transformFrom(correction, foot + seen->second.s_max * along(before.theta));
    const Vector2 d = along(out.filter.lineLandmark(out.filter.slotOf(id)).theta);
    seen->second.s_min = std::min(first.dot(d), last.dot(d));
    seen->second.s_max = std::max(first.dot(d), last.dot(d));
  }
  return out;
}

}  // namespace ekf_slam
