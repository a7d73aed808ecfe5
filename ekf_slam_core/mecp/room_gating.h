// Room gating of data association (thesis §4.4.5): every point landmark is
// labelled with the room it was mapped in, and an observation is compared
// only with landmarks of its own room, so that two features close in metric
// terms but on either side of a wall are never paired.
//
// Rooms of a point p seen from the sensor at s (landmarks at augmentation,
// observations at association, both at their estimated map positions):
// RoomMap::roomOf(p, s), the room of the first free cell on the way from p
// to s. A point on a wall's face lies in the wall's barrier; walking toward
// the sensor leaves it on the side it was seen from, so a drift across the
// wall smaller than the barrier's half-width (wall_inflation) does not
// change the label. A point within jamb_radius of a doorway's end (a door
// jamb, one feature bordering both rooms) is in both of the doorway's rooms.
// When no free cell lies on the way (the sensor stands in a doorway, whose
// opening the map draws as a barrier, and looks along the wall), the point
// is in the rooms of the doorways within doorway_radius of the sensor: an
// observation there may still pair across that wall.
//
// Why the observation's room and not the robot's: through a doorway the
// robot sees the next room's features, which then belong to that room; a
// gate on the robot's room would refuse their landmarks and map them again
// at every scan.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/filter/data_association.h"
#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/mecp/doorways.h"

namespace ekf_slam {

struct RoomGateOptions {
  double jamb_radius = 0.3;     // m: a point this close to a doorway's end borders both rooms
  double doorway_radius = 0.8;  // m: a sensor this close to a doorway's centre stands in it

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("jamb_radius", jamb_radius, Bounds::atLeast(0.0, "m"));
    v.number("doorway_radius", doorway_radius, Bounds::atLeast(0.0, "m"));
  }
  std::string validate() const { return checkFields(*this); }  // empty when valid
};

class RoomGate {
 public:
  // `rooms` built from walls with `doorways` (findDoorways on the same
  // walls); the two sides of each doorway are looked up once here.
  RoomGate(RoomMap rooms, std::vector<Doorway> doorways, const RoomGateOptions& options = {});

  // The rooms of `point` seen from `seen_from` (map frame); empty when
  // unknown (outside the map, or no free cell on the way).
  std::vector<int> roomsOf(const Vector2& point, const Vector2& seen_from) const;

  // Labels landmark `id` at `position`, seen from `seen_from`.
  void labelLandmark(int id, const Vector2& position, const Vector2& seen_from);
  // The landmark's rooms; empty when unlabelled or unknown.
  std::vector<int> landmarkRooms(int id) const;

  // Whether landmark `id` may be paired with an observation in `rooms`:
  // yes when they share a room, or when either side's room is unknown.
  bool allows(int id, const std::vector<int>& rooms) const;

  const RoomMap& rooms() const { return rooms_; }
  const std::vector<Doorway>& doorways() const { return doorways_; }

 private:
  RoomMap rooms_;
  std::vector<Doorway> doorways_;
  std::vector<std::vector<int>> doorway_rooms_;  // per doorway: the rooms on its two sides
  RoomGateOptions options_;
  std::unordered_map<int, std::vector<int>> landmark_rooms_;
};

// Association (associate(), unchanged) with each observation compared only
// with the point landmarks of its rooms. Observations are placed in the
// map at the filter's pose estimate and grouped by their rooms; each group
// is associated on a copy of the filter without the landmarks it may not
// see (marginalised: the others' predictions do not change), so those are
// never candidates, matches or reasons to leave an observation ambiguous.
// A landmark two groups both match (a jamb) keeps the smaller d²; the
// other observation becomes kAmbiguous. Landmark ids are those of `filter`.
// Costs a copy of the filter (O(n²)) per group. `observation_rooms` (if
// given) receives each observation's rooms.
AssociationResult associateInRooms(const EkfSlam& filter,
                                   const std::vector<PointObservation>& observations,
                                   const AssociationOptions& options, const RoomGate& gate,
                                   std::vector<std::vector<int>>* observation_rooms = nullptr);

}  // namespace ekf_slam
