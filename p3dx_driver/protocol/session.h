// The client side of one P2OS connection over any ByteStream: the SYNC0/1/2
// handshake with echo check (closing a session an earlier client left
// streaming), OPEN, then framed sends and packet reception.
//
// Timeouts use the steady clock; nothing blocks longer than the configured
// reply timeouts, so a silent or unplugged device is detected, never waited on
// forever.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "p3dx_driver/protocol/packet.h"
#include "serial_io/byte_stream.h"

namespace p3dx {

struct RobotIdentity {
  std::string name;         // e.g. "emulated" or the robot's configured name
  std::string robot_class;  // "Pioneer"
  std::string subclass;     // "p3dx", "p3dx-sh"
};

struct SessionOptions {
  std::chrono::milliseconds reply_timeout{300};      // per SYNC step
  int sync_attempts = 3;                             // full SYNC0..2 tries
  std::chrono::milliseconds first_sip_timeout{800};  // after OPEN
};

class Session {
 public:
  // `stream` is borrowed and must outlive the session.
  explicit Session(serial_io::ByteStream* stream, SessionOptions options = {});

  // SYNC0/1/2 then OPEN; true once the first SIP arrived. On false, error()
  // says which step failed.
  bool handshake();

  // Reads what arrives within `timeout` and appends every valid packet.
  serial_io::IoStatus receive(std::chrono::milliseconds timeout,
                              std::vector<std::vector<uint8_t>>* payloads);

  // Frames and writes one command payload.
  bool send(const std::vector<uint8_t>& payload);

  // STOP then CLOSE (best effort: the device may already be gone).
  void close();

  const RobotIdentity& identity() const { return identity_; }
  const DecoderStats& decoderStats() const { return decoder_.stats(); }
  const std::string& error() const { return error_; }
  // Stale sessions found streaming during handshakes and closed.
  int staleSessionsClosed() const { return stale_sessions_closed_; }
  // SIPs that arrived during the handshake wait for OPEN's first packet.
  std::vector<std::vector<uint8_t>>& pending() { return pending_; }

 private:
  enum class WaitResult { kMatched, kStaleSession, kTimeout, kClosed };
  // Waits for a packet whose first byte is `expected`.
  WaitResult waitFor(uint8_t expected, std::chrono::milliseconds timeout,
                     std::vector<uint8_t>* reply);
  void drain(std::chrono::milliseconds duration);

  serial_io::ByteStream* stream_;
  SessionOptions options_;
  PacketDecoder decoder_;
  std::vector<std::vector<uint8_t>> queue_;
  std::vector<std::vector<uint8_t>> pending_;
  RobotIdentity identity_;
  std::string error_;
  int stale_sessions_closed_ = 0;
};

// Splits the SYNC2 reply (after its first byte) into NUL-terminated strings.
RobotIdentity parseIdentity(const std::vector<uint8_t>& sync2_reply);

}  // namespace p3dx
