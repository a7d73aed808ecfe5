// Strategies of the filter stage (LocalFilter) beside the point landmarks:
//   RoomGatingStrategy  the point association gated by rooms (thesis §4.4.5).
// The others are wall lines as landmarks, LineLandmarks (line_landmarks.h),
// and the MECP association (mecp/mecp_association.h, landmarks: points+mecp).
#pragma once

#include <optional>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/filter/slam_iteration.h"
#include "ekf_slam_core/mecp/room_gating.h"
#include "ekf_slam_core/pipeline/line_landmarks.h"
#include "ekf_slam_core/pipeline/pipeline_options.h"

namespace ekf_slam {

struct RoomCounters {
  long room_rebuilds = 0;          // rooms.enabled: times the rooms were rebuilt …
  long room_rebuild_failures = 0;  // … and found no usable map (no walls yet, too large)
  int rooms = 0;                   // rooms in the last rebuild (0: no gating now)
  int doorways = 0;                // doorways in the last rebuild
};

// Room gating of the point association from the walls the filter has
// mapped: every rebuild_interval iterations the line landmarks' sighted
// stretches are taken as walls, doorways are found among them and the free
// space between them is split into rooms (mecp/doorways.h); each point
// landmark is labelled with the room it was seen from, and an observation
// is associated only with landmarks of its own rooms (associateInRooms).
class RoomGatingStrategy {
 public:
  explicit RoomGatingStrategy(const RoomGatingOptions& options) : options_(options) {}

  // The association to use now: gated by the rooms of the last rebuild,
  // or null (associate()) before a rebuild found rooms.
  Associator associator() const;
  // New landmarks take the room they were seen from (the laser at `laser`).
  void labelNew(const EkfSlam& filter, const IterationReport& report, const Vector2& laser);
  // After each iteration: the rooms are drawn afresh from `lines` every
  // rebuild_interval iterations.
  void afterIteration(const EkfSlam& filter, const LineLandmarks& lines);

  const RoomGate* gate() const { return gate_ ? &*gate_ : nullptr; }
  const RoomCounters& counters() const { return counters_; }

 private:
  void rebuild(const EkfSlam& filter, const LineLandmarks& lines);

  RoomGatingOptions options_;
  std::optional<RoomGate> gate_;  // once a rebuild found rooms
  long iterations_since_rebuild_ = 0;
  std::unordered_map<int, Vector2> seen_from_;  // per point landmark id, where the laser was
  RoomCounters counters_;
};

}  // namespace ekf_slam
