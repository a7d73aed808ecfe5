#include "p3dx_driver/protocol/sip.h"

#include <algorithm>
#include <cctype>

namespace p3dx {
namespace {

// Bounds-checked little-endian reader over a payload.
class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool has(size_t count) const { return position_ + count <= size_; }
  uint8_t u8() { return data_[position_++]; }
  uint16_t u16() {
    const uint16_t value = static_cast<uint16_t>(data_[position_] | (data_[position_ + 1] << 8));
    position_ += 2;
    return value;
  }
  int16_t i16() { return static_cast<int16_t>(u16()); }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t position_ = 0;
};

void put16(std::vector<uint8_t>* out, uint16_t value) {
  out->push_back(static_cast<uint8_t>(value & 0xFF));
  out->push_back(static_cast<uint8_t>(value >> 8));
}

// type x y th lvel rvel battery stallbump control flags compass sonar_count
constexpr size_t kFixedPartBytes = 1 + 2 + 2 + 2 + 2 + 2 + 1 + 2 + 2 + 2 + 1 + 1;

}  // namespace

std::optional<DriveConversions> conversionsForSubclass(const std::string& subclass) {
  std::string lower = subclass;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  DriveConversions conversions;
  if (lower == "p3dx") {
    conversions.distance_mm_per_tick = 0.485;
    return conversions;
  }
  if (lower == "p3dx-sh") {
    conversions.distance_mm_per_tick = 1.0;
    return conversions;
  }
  return std::nullopt;
}

SipError parseStandardSip(const uint8_t* payload, size_t size, StandardSip* sip) {
  if (size < 1 || !isStandardSip(payload[0])) return SipError::kNotStandardSip;
  if (size < kFixedPartBytes) return SipError::kTruncated;
  Reader in(payload, size);
  StandardSip out;
  out.type = in.u8();
  out.x_ticks = in.u16() & 0x7FFF;
  out.y_ticks = in.u16() & 0x7FFF;
  out.theta_units = in.i16();
  out.left_velocity = in.i16();
  out.right_velocity = in.i16();
  out.battery_decivolts = in.u8();
  out.stall_bump = in.u16();
  out.control = in.i16();
  out.flags = in.u16();
  out.compass = in.u8();
  const uint8_t sonar_count = in.u8();
  if (!in.has(3u * sonar_count)) return SipError::kTruncated;
  out.sonars.reserve(sonar_count);
  for (uint8_t i = 0; i < sonar_count; ++i) {
    SonarReading reading;
    reading.index = in.u8();
    reading.range_mm = in.u16();
    out.sonars.push_back(reading);
  }
  if (in.has(5)) {
    out.has_io = true;
    out.grip_state = in.u8();
    out.anport = in.u8();
    out.analog = in.u8();
    out.digin = in.u8();
    out.digout = in.u8();
    if (in.has(2)) {
      out.has_battery_x10 = true;
      out.battery_x10 = in.u16();
      if (in.has(5)) {
        out.has_extended = true;
        out.charge_state = in.u8();
        out.rotational_velocity = in.i16();
        out.fault_flags = in.u16();
      }
    }
  }
  *sip = std::move(out);
  return SipError::kNone;
}

const char* toString(SipError error) {
  switch (error) {
    case SipError::kNone:
      return "ok";
    case SipError::kNotStandardSip:
      return "not a standard SIP";
    case SipError::kTruncated:
      return "SIP shorter than its fields";
  }
  return "unknown";
}

std::vector<uint8_t> encodeStandardSip(const StandardSip& sip) {
  std::vector<uint8_t> out;
  out.reserve(kFixedPartBytes + 3 * sip.sonars.size() + 12);
  out.push_back(sip.type);
  put16(&out, sip.x_ticks & 0x7FFF);
  put16(&out, sip.y_ticks & 0x7FFF);
  put16(&out, static_cast<uint16_t>(sip.theta_units));
  put16(&out, static_cast<uint16_t>(sip.left_velocity));
  put16(&out, static_cast<uint16_t>(sip.right_velocity));
  out.push_back(sip.battery_decivolts);
  put16(&out, sip.stall_bump);
  put16(&out, static_cast<uint16_t>(sip.control));
  put16(&out, sip.flags);
  out.push_back(sip.compass);
  out.push_back(static_cast<uint8_t>(sip.sonars.size()));
  for (const SonarReading& reading : sip.sonars) {
    out.push_back(reading.index);
    put16(&out, reading.range_mm);
  }
  if (sip.has_io) {
    out.insert(out.end(), {sip.grip_state, sip.anport, sip.analog, sip.digin, sip.digout});
    if (sip.has_battery_x10) {
      put16(&out, sip.battery_x10);
      if (sip.has_extended) {
        out.push_back(sip.charge_state);
        put16(&out, static_cast<uint16_t>(sip.rotational_velocity));
        put16(&out, sip.fault_flags);
      }
    }
  }
  return out;
}

int positionDelta(uint16_t a, uint16_t b) {
  int delta = (static_cast<int>(b) - static_cast<int>(a)) & 0x7FFF;
  if (delta >= 0x4000) delta -= 0x8000;
  return delta;
}

uint16_t wrapPositionTicks(long ticks) {
  return static_cast<uint16_t>(((ticks % 0x8000) + 0x8000) % 0x8000);
}

ekf_slam::Pose2 PositionTracker::update(const StandardSip& sip,
                                        const DriveConversions& conversions) {
  if (!initialised_) {
    initialised_ = true;
    x_ticks_ = sip.x_ticks;
    y_ticks_ = sip.y_ticks;
  } else {
    x_ticks_ += positionDelta(last_x_, sip.x_ticks);
    y_ticks_ += positionDelta(last_y_, sip.y_ticks);
  }
  last_x_ = sip.x_ticks;
  last_y_ = sip.y_ticks;
  const double mm_per_tick = conversions.distance_mm_per_tick;
  return ekf_slam::Pose2(x_ticks_ * mm_per_tick * 1e-3, y_ticks_ * mm_per_tick * 1e-3,
                         sip.theta_units * conversions.angle_rad_per_unit);
}

}  // namespace p3dx
