#include "p3dx_driver/fuzz/fuzz_one_input.h"

#include <cassert>
#include <cmath>
#include <vector>

#include "p3dx_driver/emulator/p3dx_emulator.h"
#include "p3dx_driver/protocol/commands.h"
#include "p3dx_driver/protocol/packet.h"
#include "p3dx_driver/protocol/sip.h"
#include "serial_io/memory_stream.h"

namespace p3dx {

void fuzzOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return;
  // The first byte picks the chunk size, so splits at every position occur.
  const size_t chunk = 1 + data[0] % 64;
  ++data;
  --size;

  PacketDecoder decoder;
  std::vector<std::vector<uint8_t>> payloads;
  PositionTracker tracker;
  const DriveConversions conversions;
  for (size_t offset = 0; offset < size; offset += chunk) {
    const size_t count = offset + chunk <= size ? chunk : size - offset;
    decoder.feed(data + offset, count, &payloads);
    assert(decoder.buffered() <= kMaxPacketBytes + chunk);
  }
  for (const auto& payload : payloads) {
    assert(!payload.empty() && payload.size() <= kMaxPayloadBytes);
    StandardSip sip;
    if (parseStandardSip(payload.data(), payload.size(), &sip) == SipError::kNone) {
      const ekf_slam::Pose2 pose = tracker.update(sip, conversions);
      assert(pose.allFinite());
      // Re-encoding a parsed SIP and parsing it again gives the same fields.
      const std::vector<uint8_t> again = encodeStandardSip(sip);
      StandardSip reparsed;
      const SipError error = parseStandardSip(again.data(), again.size(), &reparsed);
      assert(error == SipError::kNone && reparsed.x_ticks == sip.x_ticks &&
             reparsed.sonars.size() == sip.sonars.size());
      (void)error;
    }
    decodeCommand(payload);
  }

  // The same bytes as commands to the robot: no crash, no runaway motion.
  serial_io::MemoryStream stream;
  stream.feed(std::vector<uint8_t>(data, data + size));
  EmulatorOptions options;
  options.stale_session = true;  // accept motion commands at once
  P3dxEmulator robot(&stream, options);
  for (int step = 0; step < 20; ++step) robot.step(0.05 * step);
  assert(robot.truePose().allFinite() && robot.odometryPose().allFinite());
  assert(std::abs(robot.velocity()) <= 2.2 + 1e-9);
}

}  // namespace p3dx
