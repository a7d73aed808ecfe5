#include "ekf_slam_core/mecp/room_gating.h"

#include <algorithm>
#include <utility>

namespace ekf_slam {
namespace {

void addUnique(int room, std::vector<int>* rooms) {
  if (room >= 0 && std::find(rooms->begin(), rooms->end(), room) == rooms->end()) {
    rooms->push_back(room);
  }
}

}  // namespace

RoomGate::RoomGate(RoomMap rooms, std::vector<Doorway> doorways, const RoomGateOptions& options)
    : rooms_(std::move(rooms)), doorways_(std::move(doorways)), options_(options) {
  // A doorway's sides: the rooms a step off the opening's middle, either
  // way along its normal, beyond the barrier the map draws over it.
  for (const Doorway& door : doorways_) {
    const Vector2 along = (door.end_b - door.end_a).normalized();
    const Vector2 normal(-along.y(), along.x());
    std::vector<int> sides;
    for (double side : {1.0, -1.0}) {
      addUnique(
          rooms_.roomOf(door.centre(), door.centre() + side * options_.doorway_radius * normal),
          &sides);
    }
    doorway_rooms_.push_back(sides);
  }
}

const std::vector<int>& RoomGate::moveRobot(const Vector2& position) {
  std::vector<int> now;
  for (size_t d = 0; d < doorways_.size(); ++d) {
    if ((position - doorways_[d].centre()).norm() <= options_.doorway_radius) {
      for (int room : doorway_rooms_[d]) addUnique(room, &now);
    }
  }
  addUnique(rooms_.roomAt(position), &now);
  if (!now.empty()) robot_rooms_ = std::move(now);
  return robot_rooms_;
}

void RoomGate::labelLandmark(int id, const Vector2& position, const Vector2& seen_from) {
  std::vector<int> labels;
  addUnique(rooms_.roomOf(position, seen_from), &labels);
  for (size_t d = 0; d < doorways_.size(); ++d) {
    for (const Vector2& jamb : {doorways_[d].end_a, doorways_[d].end_b}) {
      if ((position - jamb).norm() <= options_.jamb_radius) {
        for (int room : doorway_rooms_[d]) addUnique(room, &labels);
      }
    }
  }
  landmark_rooms_[id] = labels;
}

std::vector<int> RoomGate::landmarkRooms(int id) const {
  const auto it = landmark_rooms_.find(id);
  return it == landmark_rooms_.end() ? std::vector<int>() : it->second;
}

bool RoomGate::allows(int id) const {
  const auto it = landmark_rooms_.find(id);
  if (it == landmark_rooms_.end() || it->second.empty() || robot_rooms_.empty()) return true;
  for (int room : it->second) {
    if (std::find(robot_rooms_.begin(), robot_rooms_.end(), room) != robot_rooms_.end()) {
      return true;
    }
  }
  return false;
}

AssociationResult associateInRooms(const EkfSlam& filter,
                                   const std::vector<PointObservation>& observations,
                                   const AssociationOptions& options, const RoomGate& gate) {
  std::vector<int> elsewhere;
  for (const LandmarkInfo& info : filter.landmarks()) {
    if (info.kind == LandmarkKind::kPoint && !gate.allows(info.id)) elsewhere.push_back(info.id);
  }
  if (elsewhere.empty()) return associate(filter, observations, options);
  EkfSlam in_rooms = filter;
  in_rooms.removeLandmarks(elsewhere);
  return associate(in_rooms, observations, options);
}

}  // namespace ekf_slam
