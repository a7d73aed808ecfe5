#include "sick_lms200_driver/protocol/session.h"

#include <algorithm>
#include <cstdio>
#include <thread>

namespace sick_lms200 {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// Longest telegram the sensor may be sending when a request arrives; the
// reply can only follow it.
constexpr size_t kLongestTelegramBytes = 2 * kMaxValueCount + 16;

std::string hexByte(uint8_t value) {
  char text[8];
  std::snprintf(text, sizeof(text), "0x%02X", value);
  return text;
}

}  // namespace

std::string validateSessionOptions(const SessionOptions& options) {
  if (baudModeByte(options.baud) < 0) {
    return "baud: " + std::to_string(options.baud) +
           " is not an LMS200 rate (9600, 19200, 38400, 500000)";
  }
  if (options.angle_deg != 100 && options.angle_deg != 180) {
    return "angle: " + std::to_string(options.angle_deg) + " must be 100 or 180 (degrees)";
  }
  const int res = options.resolution_centideg;
  if (res != 100 && res != 50 && res != 25) {
    return "resolution: " + std::to_string(res / 100.0) + " must be 1.0, 0.5 or 0.25 (degrees)";
  }
  if (res == 25 && options.angle_deg != 100) {
    return "resolution: 0.25 degrees is only available with angle 100";
  }
  if (options.attempts < 1) return "attempts must be at least 1";
  return "";
}

Session::Session(serial_io::ByteStream& stream, std::function<bool(int)> set_host_baud,
                 TelegramDecoder& decoder, SessionOptions options)
    : stream_(stream),
      set_host_baud_(std::move(set_host_baud)),
      decoder_(decoder),
      options_(std::move(options)) {}

bool Session::fail(const std::string& message) {
  error_ = message;
  return false;
}

milliseconds Session::waitFor(milliseconds base) const {
  // Base wait plus the time a longest telegram in flight takes to send.
  return base + milliseconds(static_cast<int>(
                    1000.0 * lineTime(kLongestTelegramBytes, current_baud_) + 0.5));
}

bool Session::transact(uint8_t command, const std::vector<uint8_t>& data, Telegram* reply,
                       milliseconds timeout, int attempts) {
  const std::vector<uint8_t> request = encodeTelegram(kHostAddress, command, data);
  const uint8_t expected = static_cast<uint8_t>(command + kReplyOffset);
  std::string last_problem = "no reply";
  for (int attempt = 0; attempt < attempts; ++attempt) {
    if (stream_.write(request.data(), request.size()) != serial_io::IoStatus::kOk) {
      return fail(stream_.name() + ": write failed (device closed or unplugged)");
    }
    const auto deadline = Clock::now() + timeout;
    bool retry = false;
    while (!retry) {
      DecoderEvent event;
      while (decoder_.next(&event)) {
        if (event.kind == DecoderEvent::Kind::kNak) {
          naks_++;
          last_problem = "NAK";
          retry = true;
          break;
        }
        if (event.kind == DecoderEvent::Kind::kTelegram && event.telegram.command == expected) {
          *reply = std::move(event.telegram);
          return true;
        }
        // ACKs and streamed measured values are not the reply we wait for.
      }
      if (retry) break;
      const auto now = Clock::now();
      if (now >= deadline) break;
      uint8_t buffer[512];
      const auto left = std::chrono::duration_cast<milliseconds>(deadline - now);
      const serial_io::ReadResult result =
          stream_.read(buffer, sizeof(buffer), std::max(left, milliseconds(1)));
      if (result.status == serial_io::IoStatus::kClosed) {
        return fail(stream_.name() + ": device closed or unplugged");
      }
      decoder_.feed(buffer, result.bytes);
    }
    if (retry) pause_(milliseconds(30));  // let the sensor settle
  }
  return fail("command " + hexByte(command) + ": " + last_problem + " after " +
              std::to_string(attempts) + " attempt(s) at " + std::to_string(current_baud_) +
              " baud");
}

bool Session::setMode(uint8_t mode_byte, const std::vector<uint8_t>& extra, const char* what) {
  std::vector<uint8_t> data(1 + extra.size());
  data[0] = mode_byte;
  std::copy(extra.begin(), extra.end(), data.begin() + 1);
  Telegram reply;
  if (!transact(cmd::kModeChange, data, &reply, waitFor(options_.reply_timeout),
                options_.attempts)) {
    return fail(std::string(what) + ": " + error_);
  }
  if (reply.data.empty() || reply.data[0] != 0) {
    return fail(std::string(what) + ": sensor refused mode " + hexByte(mode_byte) +
                (reply.data.empty() ? "" : " (reply code " + hexByte(reply.data[0]) + ")"));
  }
  return true;
}

bool Session::probeBaud() {
  // Try each rate: the sensor answers "stop continuous output" only when the
  // host's rate matches its own. Two rounds, because a streaming sensor may
  // be mid-telegram the first time.
  // The configured rate comes first: after a reconnect the sensor, still
  // powered, usually keeps the rate it was switched to.
  std::vector<int> order{options_.baud};
  for (int baud : options_.probe_bauds) {
    if (baud != options_.baud) order.push_back(baud);
  }
  // A reply to the request at one rate can come late, after the host has
  // moved on to the next: a second request at the new rate confirms it.
  const auto answers = [this](milliseconds wait, int attempts) {
    Telegram reply;
    return transact(cmd::kModeChange, {mode::kRequestOnly}, &reply, waitFor(wait), attempts);
  };
  for (int round = 0; round < 2; ++round) {
    for (int baud : order) {
      if (!set_host_baud_(baud)) continue;  // e.g. 500000 not settable here
      current_baud_ = baud;
      decoder_.reset();
      // The likely rate gets the full reply time; the others a short look.
      const milliseconds wait = baud == options_.baud ? options_.reply_timeout : milliseconds(150);
      if (answers(wait, 1) && answers(options_.reply_timeout, options_.attempts)) return true;
      if (error_.find("closed") != std::string::npos) return false;
    }
  }
  return fail("no LMS200 answers on " + stream_.name() + " at any of the probed baud rates");
}

bool Session::switchBaud(int baud) {
  if (baud == current_baud_) return true;
  if (!setMode(static_cast<uint8_t>(baudModeByte(baud)), {}, "switching baud")) return false;
  if (!set_host_baud_(baud)) {
    return fail(stream_.name() + ": cannot set host baud " + std::to_string(baud));
  }
  current_baud_ = baud;
  decoder_.reset();
  pause_(milliseconds(20));
  return true;
}

bool Session::setVariant() {
  const uint16_t angle = static_cast<uint16_t>(options_.angle_deg);
  const uint16_t res = static_cast<uint16_t>(options_.resolution_centideg);
  Telegram reply;
  if (!transact(cmd::kVariant,
                {static_cast<uint8_t>(angle & 0xFF), static_cast<uint8_t>(angle >> 8),
                 static_cast<uint8_t>(res & 0xFF), static_cast<uint8_t>(res >> 8)},
                &reply, waitFor(options_.reply_timeout), options_.attempts)) {
    return fail("setting variant: " + error_);
  }
  if (reply.data.empty() || reply.data[0] != 1) {
    return fail("sensor refused variant " + std::to_string(angle) + " deg / " +
                std::to_string(res / 100.0) + " deg");
  }
  return true;
}

bool Session::setUnits() {
  Telegram config;
  if (!transact(cmd::kReadConfig, {}, &config, waitFor(options_.reply_timeout),
                options_.attempts)) {
    return fail("reading configuration: " + error_);
  }
  if (config.data.size() < kConfigSize) {
    return fail("configuration reply too short (" + std::to_string(config.data.size()) +
                " bytes, expected " + std::to_string(kConfigSize) + ")");
  }
  const uint8_t wanted = options_.units == Units::kMillimetres ? 1 : 0;
  if (config.data[kConfigUnitsIndex] == wanted) return true;
  const std::vector<uint8_t> password(kInstallationPassword, kInstallationPassword + 8);
  if (!setMode(mode::kInstallation, password, "entering installation mode")) return false;
  std::vector<uint8_t> new_config(config.data.begin(), config.data.begin() + kConfigSize);
  new_config[kConfigUnitsIndex] = wanted;
  Telegram reply;
  if (!transact(cmd::kWriteConfig, new_config, &reply, waitFor(options_.config_timeout),
                options_.attempts)) {
    return fail("writing configuration (units): " + error_);
  }
  if (reply.data.empty() || reply.data[0] != 1) return fail("sensor refused the configuration");
  // The reply echoes the configuration the sensor now holds (older
  // firmware may send the acceptance byte alone).
  if (reply.data.size() > kConfigSize && reply.data[1 + kConfigUnitsIndex] != wanted) {
    return fail("sensor accepted the configuration but reports units byte " +
                hexByte(reply.data[1 + kConfigUnitsIndex]) + ", expected " + hexByte(wanted));
  }
  return true;
}

bool Session::initialize() {
  const std::string invalid = validateSessionOptions(options_);
  if (!invalid.empty()) return fail(invalid);
  error_.clear();
  if (!probeBaud()) return false;
  if (!switchBaud(options_.baud)) return false;

  Telegram reply;
  if (!transact(cmd::kTypeString, {}, &reply, waitFor(options_.reply_timeout), options_.attempts)) {
    return fail("reading type string: " + error_);
  }
  type_string_.assign(reply.data.begin(),
                      reply.data.empty() ? reply.data.end() : reply.data.end() - 1);
  if (!transact(cmd::kStatus, {}, &reply, waitFor(options_.reply_timeout), options_.attempts)) {
    return fail("reading status: " + error_);
  }
  sensor_status_ = reply.data.empty() ? 0xFF : reply.data.back();
  if (statusSeverity(sensor_status_) >= StatusSeverity::kError) {
    return fail("sensor reports " + describeStatus(sensor_status_));
  }
  if (!setVariant()) return false;
  if (!setUnits()) return false;
  if (!setMode(mode::kContinuousAll, {}, "starting continuous output")) return false;
  error_.clear();  // a rate that did not answer while probing is no error now
  return true;
}

bool Session::stopStreaming() {
  Telegram reply;
  return transact(cmd::kModeChange, {mode::kRequestOnly}, &reply, waitFor(options_.reply_timeout),
                  1);
}

}  // namespace sick_lms200
