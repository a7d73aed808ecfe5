// The scanner's side of the LMS2xx protocol, as a step-able object: it reads
// host telegrams from a ByteStream (the master side of a pty in the
// `lms200_emulator` executable, or anything in-process), answers them, and in
// continuous mode streams 0xB0 scans of a PolygonWorld, paced at the rate the
// emulated baud allows (10 bits per byte): complete scans in mode 0x24, one
// partial scan per telegram in mode 0x2A. No ROS.
//
// Timing model (what the driver's stamp estimate assumes): a sweep starts at
// a mirror-turn boundary t0 (75 Hz), lasts sweepTime() (one turn's sweep for
// a partial scan), and its telegram starts leaving at t0 + that time, each
// byte taking 10 / baud seconds. The emulator reports t0 as the true
// first-beam time of every scan.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sim/polygon_world.h"
#include "serial_io/byte_stream.h"
#include "sick_lms200_driver/protocol/measured_values.h"
#include "sick_lms200_driver/protocol/telegram.h"

namespace sick_lms200 {

struct EmulatorOptions {
  int initial_baud = 9600;            // power-on rate of a real LMS200
  int angle_deg = 180;                // power-on variant
  int resolution_centideg = 100;      // power-on variant (1°)
  Units units = Units::kMillimetres;  // power-on units
  double range_noise_sigma = 0.01;    // m, Gaussian, on ranges that hit something
  // rad, the scanner's tilt from level (ROS roll and pitch): its beams meet
  // the walls, which are taller than any beam, further out.
  double roll = 0.0;
  double pitch = 0.0;
  std::string type_string = "LMS200;30106;V02.10 ;S01.31 ";
  double config_write_delay = 0.5;  // s between the 0x77 ACK and its reply (EEPROM write)
  // Fault injection, probabilities in [0, 1].
  double bad_crc_rate = 0.0;    // per streamed scan: checksum corrupted
  double drop_byte_rate = 0.0;  // per streamed scan: one byte lost
  double nak_rate = 0.0;        // per request: answered with NAK only
  uint32_t seed = 1;
  // Status byte ending every reply and scan. 0x10: no error, data source
  // LMS type 6 (bits 3-4 = 10), as an LMS200 sends it; 00 in bits 3-4 is
  // reserved. Another value emulates a sensor reporting it.
  uint8_t status_byte = 0x10;
};

// Ground truth of one streamed scan.
struct TrueScan {
  double first_beam_time = 0.0;  // s, emulator clock
  int angle_deg = 180;
  int resolution_centideg = 100;
  // A partial scan (mode 0x2A) holds the beams of one mirror turn, 1° apart,
  // the first one partial_offset_centideg after a complete scan's first beam.
  bool partial = false;
  int partial_offset_centideg = 0;
  std::vector<double> ranges;  // m, noise-free, +inf for no return, angular order
  std::vector<double> sent;    // m, as encoded (noise, units, reserved codes)
  int baud = 0;                // line speed it is sent at
  bool corrupted = false;      // bad checksum or dropped byte injected
};

class Lms200Emulator {
 public:
  // Pose of the sensor (laser frame) in the world at time t (s).
  using PoseSource = std::function<ekf_slam::Pose2(double t)>;
  using ScanObserver = std::function<void(const TrueScan&)>;

  Lms200Emulator(serial_io::ByteStream& stream, const ekf_slam::sim::RayCaster& world,
                 PoseSource pose_source, EmulatorOptions options);

  // The host's current line speed (e.g. PseudoTerminal::peerBaud); when it
  // differs from the emulated baud, the emulator hears garbage and the host
  // receives garbage, like a real sensor at another rate. Unset: always match.
  void setPeerBaudSource(std::function<int()> peer_baud) { peer_baud_ = std::move(peer_baud); }
  // Called when a scan starts leaving the sensor (before its bytes are sent).
  void setScanObserver(ScanObserver observer) { observer_ = std::move(observer); }
  // A silent sensor neither answers nor streams (cable cut on the sensor side).
  void setSilent(bool silent) { silent_ = silent; }

  // Handles input and sends every byte due by `now` (s, any monotonic-enough
  // clock; the same clock as the reported first-beam times).
  void spinOnce(double now);
  // Earliest time spinOnce has output work to do (for the caller's sleep).
  double nextDeadline(double now) const;

  int baud() const { return baud_; }
  bool streaming() const { return streaming_ != Streaming::kOff; }
  bool streamingPartialScans() const { return streaming_ == Streaming::kPartialScans; }
  // The mode byte of the last accepted mode change (0x25 at power-on).
  uint8_t operatingMode() const { return operating_mode_; }
  int angleDeg() const { return angle_deg_; }
  int resolutionCentideg() const { return resolution_centideg_; }
  Units units() const;
  uint64_t garbageBytesHeard() const { return garbage_heard_; }

 private:
  void handleInput(double now);
  void handleRequest(const Telegram& request, double now);
  // ACK at `start`, the reply telegram `work` seconds later.
  void reply(uint8_t request_command, const std::vector<uint8_t>& data, double start,
             double work = 0.0);
  void enqueue(const std::vector<uint8_t>& bytes, double start);
  std::vector<uint8_t> statusReplyData() const;
  void streamScans(double now);
  // Time (s) from the first to the last beam of what the current mode sends.
  double currentSweepTime() const;
  // Noise-free ranges (m) of partial k, measured in the mirror turn starting at `turn_start`.
  std::vector<double> castPartial(int k, double turn_start) const;
  void sendScan(double first_beam_time);
  void sendPartialScan(int k, double first_beam_time);
  // Adds noise, encodes `truth` and queues its telegram at `send_at`.
  void transmit(TrueScan truth, int partial_offset_quarters, double send_at);
  void flushOutput(double now);
  bool peerMatches() const;
  double byteTime() const { return 10.0 / baud_; }

  serial_io::ByteStream& stream_;
  const ekf_slam::sim::RayCaster& world_;
  PoseSource pose_source_;
  EmulatorOptions options_;
  std::function<int()> peer_baud_;
  ScanObserver observer_;
  std::mt19937 rng_;

  TelegramDecoder decoder_{kHostAddress};
  int baud_;
  int pending_baud_ = 0;  // applied once the line is free
  // What the sensor sends unasked: nothing (request mode 0x25), complete
  // scans (0x24) or partial scans (0x2A).
  enum class Streaming { kOff, kCompleteScans, kPartialScans };
  Streaming streaming_ = Streaming::kOff;
  uint8_t operating_mode_ = mode::kRequestOnly;
  bool installation_mode_ = false;
  bool silent_ = false;
  int angle_deg_;
  int resolution_centideg_;
  std::vector<uint8_t> config_;

  std::deque<std::pair<double, uint8_t>> output_;  // (time the byte is complete, byte)
  double line_free_at_ = 0.0;
  double next_sweep_start_ = -1.0;  // < 0: none scheduled
  int next_partial_ = 0;            // partial k measured next in mode 0x2A
  uint64_t garbage_heard_ = 0;
};

}  // namespace sick_lms200
