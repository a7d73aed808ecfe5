#include "ekf_slam_core/pipeline/filter_strategies.h"

#include <iterator>
#include <string>

namespace ekf_slam {

Associator RoomGatingStrategy::associator() const {
  if (!gate_) return nullptr;
  return [this](const EkfSlam& filter, const std::vector<PointObservation>& observations,
                const AssociationOptions& association) {
    return associateInRooms(filter, observations, association, *gate_);
  };
}

void RoomGatingStrategy::labelNew(const EkfSlam& filter, const IterationReport& report,
                                  const Vector2& laser) {
  for (const PointMatch& created : report.created) {
    const int slot = filter.slotOf(created.landmark_id);
    if (slot < 0) continue;
    seen_from_[created.landmark_id] = laser;
    if (gate_) gate_->labelLandmark(created.landmark_id, filter.landmarkPosition(slot), laser);
  }
}

void RoomGatingStrategy::afterIteration(const EkfSlam& filter, const LineLandmarks& lines) {
  if (++iterations_since_rebuild_ >= options_.rebuild_interval) rebuild(filter, lines);
}

// The walls mapped so far (the line landmarks' sighted stretches) with
// their doorways make the rooms; a gap is a doorway only where no mapped
// wall stands across the way through it (crossesNoWall). The map moves as the filter corrects it,
// so the rooms are drawn afresh and every point landmark is labelled again
// from where it was first seen. A map that cannot be drawn (no walls yet,
// an extent beyond rooms.map.max_cells) leaves the association ungated.
void RoomGatingStrategy::rebuild(const EkfSlam& filter, const LineLandmarks& lines) {
  iterations_since_rebuild_ = 0;
  ++counters_.room_rebuilds;
  for (auto it = seen_from_.begin(); it != seen_from_.end();) {
    it = filter.slotOf(it->first) < 0 ? seen_from_.erase(it) : std::next(it);
  }
  const std::vector<Segment2> walls = lines.walls(filter);
  const std::vector<Doorway> doorways =
      findDoorways(walls, options_.doorways, crossesNoWall(walls));
  RoomMap rooms;
  const std::string error =
      walls.empty() ? "no walls mapped" : rooms.build(walls, doorways, options_.map);
  if (!error.empty()) {
    gate_.reset();
    ++counters_.room_rebuild_failures;
    counters_.rooms = 0;
    counters_.doorways = 0;
    return;
  }
  counters_.rooms = rooms.roomCount();
  counters_.doorways = static_cast<int>(doorways.size());
  gate_.emplace(std::move(rooms), doorways, options_.gate);
  for (const auto& [id, seen_from] : seen_from_) {
    gate_->labelLandmark(id, filter.landmarkPosition(filter.slotOf(id)), seen_from);
  }
}

}  // namespace ekf_slam
