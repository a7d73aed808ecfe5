// Host side of the LMS2xx command protocol over a ByteStream: request/reply
// transactions with bounded waits and retries, baud probing and switching,
// and the initialisation sequence (type, status, variant, units, continuous
// output). Blocking; meant for a driver's I/O thread. No ROS.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "serial_io/byte_stream.h"
#include "sick_lms200_driver/protocol/measured_values.h"
#include "sick_lms200_driver/protocol/telegram.h"

namespace sick_lms200 {

// Index, in the 0x74/0x77 configuration data (after the command byte), of
// the byte selecting the units (0 = cm, 1 = mm).
constexpr size_t kConfigUnitsIndex = 6;
// ... of the measuring mode (0 = 8 m/80 m range with fields A, B and dazzle;
// others trade range bits for flag bits), the restart mode and restart time.
constexpr size_t kConfigMeasuringModeIndex = 5;
constexpr size_t kConfigRestartModeIndex = 10;
constexpr size_t kConfigRestartTimeIndex = 11;
constexpr size_t kConfigSize = 34;
constexpr char kInstallationPassword[] = "SICK_LMS";

struct SessionOptions {
  int baud = 38400;                              // line speed to switch to: 9600/19200/38400/500000
  int angle_deg = 180;                           // scan angle: 100 or 180
  int resolution_centideg = 100;                 // 100 (1°), 50 (0.5°), 25 (0.25°, 100° only)
  Units units = Units::kMillimetres;             // mm: 8.18 m max, cm: 81.8 m max
  std::chrono::milliseconds reply_timeout{400};  // per attempt, on top of line time
  std::chrono::milliseconds config_timeout{5000};  // writing the configuration is slow
  int attempts = 3;                                // per request
  std::vector<int> probe_bauds{9600, 38400, 19200, 500000};
};

// Empty when valid, else a message naming the bad field.
std::string validateSessionOptions(const SessionOptions& options);

// Time (s) to send `bytes` bytes at `baud` (8N1: 10 bits per byte).
inline double lineTime(size_t bytes, int baud) { return bytes * 10.0 / baud; }

class Session {
 public:
  // `set_host_baud` changes the host's line speed (SerialPort::setBaud);
  // `decoder` is shared with the caller's streaming loop so no byte is lost.
  Session(serial_io::ByteStream& stream, std::function<bool(int)> set_host_baud,
          TelegramDecoder& decoder, SessionOptions options);

  // Finds the sensor, switches baud, configures it and starts continuous
  // output. Returns false with error() set; the caller may retry.
  bool initialize();
  // Asks the sensor to stop continuous output (best effort).
  bool stopStreaming();

  // One request/reply exchange: sends the telegram and waits for the reply
  // (command + 0x80), resending after a NAK or a timeout, up to `attempts`.
  bool transact(uint8_t command, const std::vector<uint8_t>& data, Telegram* reply,
                std::chrono::milliseconds timeout, int attempts);

  int currentBaud() const { return current_baud_; }
  const std::string& typeString() const { return type_string_; }
  uint8_t sensorStatus() const { return sensor_status_; }
  const std::string& error() const { return error_; }
  uint64_t naks() const { return naks_; }

  // Replaces the settling pauses (after a NAK, after a baud change), which
  // are std::this_thread::sleep_for by default. For a fuzzer that feeds
  // replies from memory and must not spend wall time.
  void setPause(std::function<void(std::chrono::milliseconds)> pause) { pause_ = std::move(pause); }

 private:
  bool probeBaud();
  bool switchBaud(int baud);
  bool setMode(uint8_t mode_byte, const std::vector<uint8_t>& extra, const char* what);
  bool setVariant();
  bool setUnits();
  bool fail(const std::string& message);
  std::chrono::milliseconds waitFor(std::chrono::milliseconds base) const;

  serial_io::ByteStream& stream_;
  std::function<bool(int)> set_host_baud_;
  TelegramDecoder& decoder_;
  SessionOptions options_;
  int current_baud_ = 9600;
  std::string type_string_;
  uint8_t sensor_status_ = 0;
  std::string error_;
  uint64_t naks_ = 0;
  std::function<void(std::chrono::milliseconds)> pause_ = [](std::chrono::milliseconds wait) {
    std::this_thread::sleep_for(wait);
  };
};

}  // namespace sick_lms200
