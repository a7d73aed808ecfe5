#include "p3dx_driver/protocol/session.h"

#include <algorithm>

#include "p3dx_driver/protocol/commands.h"
#include "p3dx_driver/protocol/sip.h"

namespace p3dx {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

RobotIdentity parseIdentity(const std::vector<uint8_t>& reply) {
  std::vector<std::string> fields;
  std::string current;
  for (size_t i = 1; i < reply.size(); ++i) {
    if (reply[i] == 0) {
      fields.push_back(current);
      current.clear();
    } else {
      current.push_back(static_cast<char>(reply[i]));
    }
  }
  if (!current.empty()) fields.push_back(current);
  RobotIdentity identity;
  if (fields.size() > 0) identity.name = fields[0];
  if (fields.size() > 1) identity.robot_class = fields[1];
  if (fields.size() > 2) identity.subclass = fields[2];
  return identity;
}

Session::Session(serial_io::ByteStream* stream, SessionOptions options)
    : stream_(stream), options_(options) {}

bool Session::send(const std::vector<uint8_t>& payload) {
  const std::vector<uint8_t> packet = encodePacket(payload);
  if (stream_->write(packet.data(), packet.size()) != serial_io::IoStatus::kOk) {
    error_ = stream_->name() + ": write failed (device gone?)";
    return false;
  }
  return true;
}

serial_io::IoStatus Session::receive(milliseconds timeout,
                                     std::vector<std::vector<uint8_t>>* payloads) {
  uint8_t buffer[256];
  const serial_io::ReadResult result = stream_->read(buffer, sizeof(buffer), timeout);
  if (result.status == serial_io::IoStatus::kClosed) {
    error_ = stream_->name() + ": device closed or unplugged";
    return result.status;
  }
  if (result.bytes > 0) decoder_.feed(buffer, result.bytes, payloads);
  return result.status;
}

Session::WaitResult Session::waitFor(uint8_t expected, milliseconds timeout,
                                     std::vector<uint8_t>* reply) {
  const Clock::time_point deadline = Clock::now() + timeout;
  while (true) {
    for (size_t i = 0; i < queue_.size(); ++i) {
      const std::vector<uint8_t> packet = queue_[i];
      if (packet.empty()) continue;
      if (packet[0] == expected) {
        queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(i) + 1);
        *reply = packet;
        return WaitResult::kMatched;
      }
      if (isServerInfoPacket(packet[0])) {
        queue_.clear();
        return WaitResult::kStaleSession;
      }
    }
    queue_.clear();
    const Clock::time_point now = Clock::now();
    if (now >= deadline) return WaitResult::kTimeout;
    const auto left = std::chrono::duration_cast<milliseconds>(deadline - now);
    if (receive(std::max(left, milliseconds(1)), &queue_) == serial_io::IoStatus::kClosed) {
      return WaitResult::kClosed;
    }
  }
}

void Session::drain(milliseconds duration) {
  const Clock::time_point deadline = Clock::now() + duration;
  std::vector<std::vector<uint8_t>> ignored;
  while (Clock::now() < deadline) {
    if (receive(milliseconds(20), &ignored) == serial_io::IoStatus::kClosed) return;
    ignored.clear();
  }
  decoder_.clear();
}

bool Session::handshake() {
  error_.clear();
  queue_.clear();
  pending_.clear();
  decoder_.clear();
  for (int attempt = 0; attempt < options_.sync_attempts; ++attempt) {
    int step = 0;
    int closes = 0;
    std::vector<uint8_t> reply;
    while (step < 3) {
      if (!send(encodeCommand(static_cast<Command>(step)))) return false;
      const WaitResult result = waitFor(static_cast<uint8_t>(step), options_.reply_timeout, &reply);
      if (result == WaitResult::kClosed) return false;
      if (result == WaitResult::kTimeout) {
        error_ = stream_->name() + ": no echo of SYNC" + std::to_string(step) + " within " +
                 std::to_string(options_.reply_timeout.count()) + " ms (wrong baud or robot off?)";
        break;
      }
      if (result == WaitResult::kStaleSession) {
        // An earlier client left the robot streaming: close that session.
        if (++closes > 2) {
          error_ = stream_->name() + ": robot keeps streaming after CLOSE (wrong baud?)";
          break;
        }
        ++stale_sessions_closed_;
        if (!send(encodeCommand(Command::kClose))) return false;
        drain(milliseconds(200));
        step = 0;
        continue;
      }
      if (step == 2) identity_ = parseIdentity(reply);
      ++step;
    }
    if (step < 3) continue;
    if (!send(encodeCommand(Command::kOpen))) return false;
    const Clock::time_point deadline = Clock::now() + options_.first_sip_timeout;
    while (Clock::now() < deadline) {
      std::vector<std::vector<uint8_t>> packets;
      if (receive(milliseconds(20), &packets) == serial_io::IoStatus::kClosed) return false;
      for (auto& packet : packets) {
        if (!packet.empty() && isStandardSip(packet[0])) pending_.push_back(std::move(packet));
      }
      if (!pending_.empty()) return true;
    }
    error_ = stream_->name() + ": synchronised with " + identity_.name +
             " but no SIP arrived after OPEN";
  }
  return false;
}

void Session::close() {
  send(encodeCommand(Command::kStop));
  send(encodeCommand(Command::kClose));
}

}  // namespace p3dx
