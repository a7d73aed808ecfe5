// Room gating of data association (thesis §4.4.5): every point landmark is
// labelled with the room it was mapped in, and an observation is only
// compared with landmarks of the rooms the robot is in, so that two features
// close in metric terms but on either side of a wall are never paired.
//
// The robot's rooms: the room of its position in the RoomMap; when it
// stands within doorway_radius of a doorway's centre (where the map draws
// the opening as a barrier, and where it sees into both rooms) both rooms
// the doorway joins; when its position falls on a barrier elsewhere (a
// drifting estimate against a wall) the rooms it was last in.
// A landmark's rooms: roomOf(landmark, robot position) at augmentation; a
// landmark within jamb_radius of a doorway's end (a door jamb, one feature
// that borders both rooms) carries both of that doorway's rooms. A landmark
// without a label (room unknown) is never excluded.
#pragma once

#include <unordered_map>
#include <vector>

#include "ekf_slam_core/filter/data_association.h"
#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/mecp/doorways.h"

namespace ekf_slam {

struct RoomGateOptions {
  double doorway_radius = 0.8;  // m: robot this close to a doorway's centre is in both rooms
  double jamb_radius = 0.3;     // m: landmark this close to a doorway's end borders both rooms
};

class RoomGate {
 public:
  // `rooms` built from `walls` with `doorways` (findDoorways on the same
  // walls); the sides of each doorway are looked up once here.
  RoomGate(RoomMap rooms, std::vector<Doorway> doorways, const RoomGateOptions& options = {});

  // Moves the robot to `position` (map frame); returns the rooms it is in
  // now (empty until its position has once been in a room).
  const std::vector<int>& moveRobot(const Vector2& position);
  const std::vector<int>& robotRooms() const { return robot_rooms_; }

  // Labels landmark `id` at `position`, seen from `seen_from`.
  void labelLandmark(int id, const Vector2& position, const Vector2& seen_from);
  // The landmark's rooms; empty when unlabelled or its room is unknown.
  std::vector<int> landmarkRooms(int id) const;

  // Whether landmark `id` may be an association candidate for the robot's
  // current rooms: unlabelled landmarks and an unknown robot room allow it.
  bool allows(int id) const;

  const RoomMap& rooms() const { return rooms_; }
  const std::vector<Doorway>& doorways() const { return doorways_; }

 private:
  RoomMap rooms_;
  std::vector<Doorway> doorways_;
  std::vector<std::vector<int>> doorway_rooms_;  // per doorway: the rooms on its two sides
  RoomGateOptions options_;
  std::vector<int> robot_rooms_;
  std::unordered_map<int, std::vector<int>> landmark_rooms_;
};

// Association (associate(), unchanged) among the point landmarks the gate
// allows: the landmarks of other rooms are removed from a copy of the
// filter (marginalised: the others' predictions do not change), so they
// never become candidates, matches or reasons to leave an observation
// ambiguous. Landmark ids in the result are those of `filter`. Costs a copy
// of the filter (O(n²)) per call.
AssociationResult associateInRooms(const EkfSlam& filter,
                                   const std::vector<PointObservation>& observations,
                                   const AssociationOptions& options, const RoomGate& gate);

}  // namespace ekf_slam
