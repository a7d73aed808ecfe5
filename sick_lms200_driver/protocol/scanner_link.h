// The driver's I/O loop without ROS: owns the serial port, (re)connects and
// initialises the sensor, decodes the stream of measured values and hands
// complete, checksum-valid scans with an estimated first-beam time to a
// callback. Device errors are reported in stats() and followed by a
// reconnect; nothing is thrown.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "serial_io/serial_port.h"
#include "sick_lms200_driver/protocol/measured_values.h"
#include "sick_lms200_driver/protocol/session.h"
#include "sick_lms200_driver/protocol/stamp_filter.h"
#include "sick_lms200_driver/protocol/telegram.h"

namespace sick_lms200 {

constexpr double kMirrorPeriod = 1.0 / 75.0;  // s per mirror turn (75 Hz)

// Time (s) from the first to the last beam of a full scan in mode 0x24: an
// interlaced scan (0.5°/0.25°) spans extra mirror turns.
double sweepTime(int angle_deg, int resolution_centideg);
// LaserScan::time_increment (s): sweepTime / (count - 1), so that the stamp
// plus (count - 1) increments is the time of the last beam. Exact for 1°
// scans; for interlaced scans neighbouring beams come from different mirror
// turns and this is the average spacing.
double beamTimeIncrement(int angle_deg, int resolution_centideg);
// Bytes of one full-scan measured-values telegram (with STX..CRC).
size_t scanTelegramBytes(int angle_deg, int resolution_centideg);
// Scans per second the sensor can deliver at `baud` (link- or mirror-bound).
double expectedScanRate(int angle_deg, int resolution_centideg, int baud);

struct LinkOptions {
  std::string port = "/dev/ttyUSB0";
  SessionOptions session;
  double time_offset = 0.0;      // s, added to every estimated first-beam time
  double reconnect_delay = 1.0;  // s between failed initialisations (absent device: 0.2 s)
  double data_timeout = 1.0;     // s without a valid scan before re-initialising
  bool filter_stamps = true;     // remove host read delays (see StampFilter)
};

struct LaserScanData {
  double first_beam_time = 0.0;  // s on the caller's clock (estimated)
  double sweep_time = 0.0;       // s, first to last beam
  double time_increment = 0.0;   // s, see beamTimeIncrement()
  int angle_deg = 180;
  int resolution_centideg = 100;
  int baud = 9600;        // line speed the scan arrived at
  MeasuredValues values;  // ranges in metres (REP-117) and raw words
};

enum class LinkState { kDisconnected, kInitialising, kStreaming };
const char* linkStateName(LinkState state);

struct LinkStats {
  LinkState state = LinkState::kDisconnected;
  int baud = 0;
  std::string type_string;
  uint8_t sensor_status = 0;
  bool have_status = false;
  uint64_t scans = 0;       // scans handed to the callback
  uint64_t crc_errors = 0;  // failed checksums (telegram dropped)
  uint64_t bad_frames = 0;  // impossible header (resynchronised)
  uint64_t discarded_bytes = 0;
  uint64_t malformed_scans = 0;  // valid checksum but inconsistent content
  uint64_t status_rejected = 0;  // scans dropped for a sensor error status
  uint64_t connects = 0;         // successful initialisations
  uint64_t link_losses = 0;      // unplugs, device errors, silences
  std::string last_error;
};

class ScannerLink {
 public:
  using ScanCallback = std::function<void(const LaserScanData&)>;
  using ClockFn = std::function<double()>;  // the stamp clock (e.g. ROS time), s

  ScannerLink(LinkOptions options, ClockFn clock, ScanCallback on_scan);
  ~ScannerLink();

  // Runs one step of the connection state machine; blocks at most about
  // 100 ms when streaming, several seconds while initialising.
  void spinOnce();
  // Stops continuous output (best effort) and closes the port.
  void shutdown();

  LinkStats stats() const;

 private:
  void connect();
  void stream();
  void handleTelegram(const DecoderEvent& event, double read_time, uint64_t bytes_fed);
  void lose(const std::string& why);
  void setError(const std::string& why);
  void syncDecoderStats();

  LinkOptions options_;
  ClockFn clock_;
  ScanCallback on_scan_;
  serial_io::SerialPort port_;
  TelegramDecoder decoder_{kSensorAddress};
  std::unique_ptr<Session> session_;
  std::chrono::steady_clock::time_point next_attempt_{};
  std::chrono::steady_clock::time_point last_scan_{};
  StampFilter stamp_filter_{kMirrorPeriod};

  mutable std::mutex mutex_;
  LinkStats stats_;
};

}  // namespace sick_lms200
