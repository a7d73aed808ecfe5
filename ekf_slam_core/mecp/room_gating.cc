#include "ekf_slam_core/mecp/room_gating.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <utility>

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {
namespace {

// m: how far off a doorway's opening its sides are looked up, beyond the
// barrier the room map draws over the opening.
constexpr double kDoorwaySideStep = 0.5;

void addUnique(int room, std::vector<int>* rooms) {
  if (room >= 0 && std::find(rooms->begin(), rooms->end(), room) == rooms->end()) {
    rooms->push_back(room);
  }
}

bool shareOne(const std::vector<int>& a, const std::vector<int>& b) {
  for (int room : a) {
    if (std::find(b.begin(), b.end(), room) != b.end()) return true;
  }
  return false;
}

}  // namespace

RoomGate::RoomGate(RoomMap rooms, std::vector<Doorway> doorways, const RoomGateOptions& options)
    : rooms_(std::move(rooms)), doorways_(std::move(doorways)), options_(options) {
  assert(options_.validate().empty());
  for (const Doorway& door : doorways_) {
    const Vector2 along = (door.end_b - door.end_a).normalized();
    const Vector2 normal(-along.y(), along.x());
    std::vector<int> sides;
    for (double side : {1.0, -1.0}) {
      addUnique(rooms_.roomOf(door.centre(), door.centre() + side * kDoorwaySideStep * normal),
                &sides);
    }
    doorway_rooms_.push_back(sides);
  }
}

std::vector<int> RoomGate::roomsOf(const Vector2& point, const Vector2& seen_from) const {
  std::vector<int> rooms;
  addUnique(rooms_.roomOf(point, seen_from), &rooms);
  for (size_t d = 0; d < doorways_.size(); ++d) {
    for (const Vector2& jamb : {doorways_[d].end_a, doorways_[d].end_b}) {
      if ((point - jamb).norm() <= options_.jamb_radius) {
        for (int room : doorway_rooms_[d]) addUnique(room, &rooms);
      }
    }
  }
  if (rooms.empty()) {
    for (size_t d = 0; d < doorways_.size(); ++d) {
      if ((seen_from - doorways_[d].centre()).norm() <= options_.doorway_radius) {
        for (int room : doorway_rooms_[d]) addUnique(room, &rooms);
      }
    }
  }
  std::sort(rooms.begin(), rooms.end());
  return rooms;
}

void RoomGate::labelLandmark(int id, const Vector2& position, const Vector2& seen_from) {
  landmark_rooms_[id] = roomsOf(position, seen_from);
}

std::vector<int> RoomGate::landmarkRooms(int id) const {
  const auto it = landmark_rooms_.find(id);
  return it == landmark_rooms_.end() ? std::vector<int>() : it->second;
}

bool RoomGate::allows(int id, const std::vector<int>& rooms) const {
  const auto it = landmark_rooms_.find(id);
  if (it == landmark_rooms_.end() || it->second.empty() || rooms.empty()) return true;
  return shareOne(it->second, rooms);
}

AssociationResult associateInRooms(const EkfSlam& filter,
                                   const std::vector<PointObservation>& observations,
                                   const AssociationOptions& options, const RoomGate& gate,
                                   std::vector<std::vector<int>>* observation_rooms) {
  const Pose2 sensor = compose(filter.pose(), filter.options().laser_pose);
  std::map<std::vector<int>, std::vector<int>> groups;  // rooms → observation indices
  std::vector<std::vector<int>> rooms_of(observations.size());
  for (size_t i = 0; i < observations.size(); ++i) {
    const RangeBearing& z = observations[i].z;
    const Vector2 point = transformFrom(
        sensor, Vector2(z.range * std::cos(z.bearing), z.range * std::sin(z.bearing)));
    rooms_of[i] = gate.roomsOf(point, sensor.translation());
    groups[rooms_of[i]].push_back(static_cast<int>(i));
  }
  if (observation_rooms) *observation_rooms = rooms_of;

  AssociationResult result;
  result.gate = chiSquareQuantile(options.gate_probability, 2.0);
  result.new_landmark_gate = chiSquareQuantile(options.new_landmark_probability, 2.0);
  result.observations.resize(observations.size());
  for (const auto& group : groups) {
    std::vector<int> elsewhere;
    for (const LandmarkInfo& info : filter.landmarks()) {
      if (info.kind == LandmarkKind::kPoint && !gate.allows(info.id, group.first)) {
        elsewhere.push_back(info.id);
      }
    }
    std::vector<PointObservation> subset;
    for (int i : group.second) subset.push_back(observations[i]);
    AssociationResult part;
    if (elsewhere.empty()) {
      part = associate(filter, subset, options);
    } else {
      EkfSlam in_rooms = filter;
      in_rooms.removeLandmarks(elsewhere);
      part = associate(in_rooms, subset, options);
    }
    result.jcbb_nodes += part.jcbb_nodes;
    for (size_t k = 0; k < group.second.size(); ++k) {
      result.observations[group.second[k]] = part.observations[k];
    }
  }

  // One landmark per scan: a landmark two groups matched stays with the
  // closer observation.
  std::map<int, int> matched_by;  // landmark id → observation index
  for (size_t i = 0; i < result.observations.size(); ++i) {
    ObservationAssociation& o = result.observations[i];
    if (o.decision != AssociationDecision::kMatched) continue;
    const auto [it, fresh] = matched_by.emplace(o.landmark_id, static_cast<int>(i));
    if (fresh) continue;
    ObservationAssociation& other = result.observations[it->second];
    ObservationAssociation& loser = other.mahalanobis2 <= o.mahalanobis2 ? o : other;
    if (&loser == &other) it->second = static_cast<int>(i);
    loser.decision = AssociationDecision::kAmbiguous;
    loser.landmark_id = -1;
  }
  return result;
}

}  // namespace ekf_slam
