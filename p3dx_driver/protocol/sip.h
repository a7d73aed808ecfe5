// Standard server information packet (SIP, type 0x32 stopped / 0x33 moving):
// parser for the driver, encoder for the emulator, the per-subclass
// conversion factors and the 15-bit position unwrapping.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace p3dx {

constexpr uint8_t kSipStopped = 0x32;
constexpr uint8_t kSipMoving = 0x33;
constexpr uint8_t kConfigPacket = 0x20;
inline bool isStandardSip(uint8_t type) { return type == kSipStopped || type == kSipMoving; }
// Any robot-originated data packet (0x30-0x3F); seeing one while syncing
// means an earlier session is still streaming.
inline bool isServerInfoPacket(uint8_t type) { return (type & 0xF0) == 0x30; }

// Conversion factors of one robot model.
struct DriveConversions {
  double distance_mm_per_tick = 0.485;   // XPOS/YPOS units (p3dx: 0.485, p3dx-sh: 1.0)
  double angle_rad_per_unit = 0.001534;  // THPOS units (2π/4096)
  double velocity_mm_s_per_unit = 1.0;   // L VEL / R VEL units
  double diff_conv = 0.0056;             // ω = (vR − vL) / 2 × diff_conv, rad/s per mm/s

  // Distance between the wheels implied by diff_conv, mm.
  double axleTrackMm() const { return 2.0 / diff_conv; }
};

// Factors for a reported subclass ("p3dx", "p3dx-sh", case-insensitive);
// nullopt for a subclass this driver has no table for.
std::optional<DriveConversions> conversionsForSubclass(const std::string& subclass);

struct SonarReading {
  uint8_t index = 0;
  uint16_t range_mm = 0;
};

struct StandardSip {
  uint8_t type = kSipStopped;
  uint16_t x_ticks = 0;  // 15 significant bits
  uint16_t y_ticks = 0;  // 15 significant bits
  int16_t theta_units = 0;
  int16_t left_velocity = 0;   // mm/s (× velocity_mm_s_per_unit)
  int16_t right_velocity = 0;  // mm/s
  uint8_t battery_decivolts = 0;
  uint16_t stall_bump = 0;
  int16_t control = 0;
  uint16_t flags = 0;
  uint8_t compass = 0;
  std::vector<SonarReading> sonars;
  // Optional trailing fields (present when the packet is long enough).
  bool has_io = false;
  uint8_t grip_state = 0, anport = 0, analog = 0, digin = 0, digout = 0;
  bool has_battery_x10 = false;
  uint16_t battery_x10 = 0;  // decivolts × 10
  bool has_extended = false;
  uint8_t charge_state = 0;
  int16_t rotational_velocity = 0;  // 0.1 °/s
  uint16_t fault_flags = 0;

  bool motorsEnabled() const { return flags & 0x0001; }
  bool emergencyStop() const { return flags & 0x0020; }
  bool leftStall() const { return stall_bump & 0x0001; }
  bool rightStall() const { return stall_bump & 0x0100; }
  uint8_t rearBumpers() const { return (stall_bump >> 1) & 0x7F; }
  uint8_t frontBumpers() const { return (stall_bump >> 9) & 0x7F; }
  // Battery voltage (V), from the finer BATTERYX10 field when present.
  double batteryVolts() const {
    return has_battery_x10 ? battery_x10 / 100.0 : battery_decivolts / 10.0;
  }
};

enum class SipError { kNone, kNotStandardSip, kTruncated };

// Parses a payload (starting at the type byte). Extra trailing bytes beyond
// the known fields are ignored; a missing optional group is reported by its
// has_* flag. Never reads outside `payload`.
SipError parseStandardSip(const uint8_t* payload, size_t size, StandardSip* sip);
const char* toString(SipError error);

// Encodes a SIP payload with every field above (optional groups included
// when their has_* flag is set).
std::vector<uint8_t> encodeStandardSip(const StandardSip& sip);

// Signed difference b − a of two 15-bit position counters, in ticks.
int positionDelta(uint16_t a, uint16_t b);
// The 15-bit counter for a position in ticks (wraps modulo 0x8000).
uint16_t wrapPositionTicks(long ticks);

// Turns the robot's wrapping counters into a continuous pose (m, rad) in the
// robot's own odometry frame. The first SIP after reset() is the origin of
// the unwrapped x/y; θ is taken as reported.
class PositionTracker {
 public:
  void reset() { initialised_ = false; }
  ekf_slam::Pose2 update(const StandardSip& sip, const DriveConversions& conversions);
  bool initialised() const { return initialised_; }

 private:
  bool initialised_ = false;
  uint16_t last_x_ = 0, last_y_ = 0;
  long x_ticks_ = 0, y_ticks_ = 0;
};

}  // namespace p3dx
