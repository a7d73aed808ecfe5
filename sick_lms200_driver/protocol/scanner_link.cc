#include "sick_lms200_driver/protocol/scanner_link.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace sick_lms200 {
namespace {
using Clock = std::chrono::steady_clock;

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}
}  // namespace

double sweepTime(int angle_deg, int resolution_centideg) {
  const int turns = 100 / resolution_centideg;
  return (turns - 1) * kMirrorPeriod + kMirrorPeriod * angle_deg / 360.0;
}

double beamTimeIncrement(int angle_deg, int resolution_centideg) {
  const int count = angle_deg * 100 / resolution_centideg + 1;
  return sweepTime(angle_deg, resolution_centideg) / (count - 1);
}

size_t scanTelegramBytes(int angle_deg, int resolution_centideg) {
  const size_t count = static_cast<size_t>(angle_deg * 100 / resolution_centideg + 1);
  return kTelegramOverhead + 1 /*CMD*/ + 2 /*info*/ + 2 * count + 1 /*status*/;
}

double expectedScanRate(int angle_deg, int resolution_centideg, int baud) {
  const double link_period = lineTime(scanTelegramBytes(angle_deg, resolution_centideg), baud);
  const double mirror_period = (100 / resolution_centideg) * kMirrorPeriod;
  // The sensor sends the newest complete scan once the line is free: a new
  // scan is measured while the previous one is sent.
  const double period = std::max(link_period, mirror_period);
  return 1.0 / (std::ceil(period / mirror_period - 1e-9) * mirror_period);
}

const char* linkStateName(LinkState state) {
  switch (state) {
    case LinkState::kDisconnected:
      return "disconnected";
    case LinkState::kInitialising:
      return "initialising";
    case LinkState::kStreaming:
      return "streaming";
  }
  return "?";
}

ScannerLink::ScannerLink(LinkOptions options, ClockFn clock, ScanCallback on_scan)
    : options_(std::move(options)), clock_(std::move(clock)), on_scan_(std::move(on_scan)) {}

ScannerLink::~ScannerLink() { port_.close(); }

LinkStats ScannerLink::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void ScannerLink::syncDecoderStats() {
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.crc_errors = decoder_.stats().crc_errors;
  stats_.bad_frames = decoder_.stats().bad_frames;
  stats_.discarded_bytes = decoder_.stats().discarded_bytes;
}

void ScannerLink::setError(const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.last_error = why;
}

void ScannerLink::lose(const std::string& why) {
  port_.close();
  session_.reset();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.state = LinkState::kDisconnected;
  stats_.link_losses++;
  stats_.last_error = why;
  next_attempt_ = Clock::now() + seconds(0.2);
}

void ScannerLink::spinOnce() {
  if (port_.isOpen() && session_ && stats().state == LinkState::kStreaming) {
    stream();
    return;
  }
  connect();
}

void ScannerLink::connect() {
  const auto now = Clock::now();
  if (now < next_attempt_) {
    std::this_thread::sleep_for(std::min<Clock::duration>(next_attempt_ - now, seconds(0.1)));
    return;
  }
  if (!port_.open(options_.port, 9600)) {
    // No device yet (an adapter still unplugged): opening is harmless, so
    // look again soon and catch the replug within 0.2 s.
    next_attempt_ = now + seconds(std::min(options_.reconnect_delay, 0.2));
    setError(port_.error());
    return;
  }
  next_attempt_ = now + seconds(options_.reconnect_delay);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.state = LinkState::kInitialising;
  }
  decoder_.reset();
  session_ = std::make_unique<Session>(
      port_, [this](int baud) { return port_.setBaud(baud); }, decoder_, options_.session);
  const bool initialised = session_->initialize();
  syncDecoderStats();
  if (!initialised) {
    const std::string why = options_.port + ": initialisation failed: " + session_->error();
    port_.close();
    session_.reset();
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.state = LinkState::kDisconnected;
    stats_.last_error = why;
    return;
  }
  last_scan_ = Clock::now();
  stamp_filter_.reset();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.state = LinkState::kStreaming;
  stats_.baud = session_->currentBaud();
  stats_.type_string = session_->typeString();
  stats_.sensor_status = session_->sensorStatus();
  stats_.have_status = true;
  stats_.connects++;
}

void ScannerLink::stream() {
  uint8_t buffer[1024];
  const serial_io::ReadResult result =
      port_.read(buffer, sizeof(buffer), std::chrono::milliseconds(100));
  const double read_time = clock_();
  if (result.status == serial_io::IoStatus::kClosed) {
    lose(options_.port + ": device closed or unplugged; reconnecting");
    return;
  }
  decoder_.feed(buffer, result.bytes);
  DecoderEvent event;
  while (decoder_.next(&event)) {
    if (event.kind == DecoderEvent::Kind::kTelegram) {
      handleTelegram(event, read_time, decoder_.bytesFed());
    }
  }
  syncDecoderStats();
  const double silent_for = std::chrono::duration<double>(Clock::now() - last_scan_).count();
  const double period =
      1.0 / expectedScanRate(options_.session.angle_deg, options_.session.resolution_centideg,
                             session_->currentBaud());
  if (silent_for > std::max(options_.data_timeout, 3.0 * period)) {
    lose(options_.port + ": no valid scan for " + std::to_string(silent_for) +
         " s; re-initialising the sensor");
  }
}

void ScannerLink::handleTelegram(const DecoderEvent& event, double read_time, uint64_t bytes_fed) {
  if (event.telegram.command != cmd::kMeasuredValues) return;  // a late reply
  LaserScanData scan;
  std::string error;
  if (!parseMeasuredValues(event.telegram, &scan.values, &error)) {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.malformed_scans++;
    stats_.last_error = "dropped a measured-values telegram: " + error;
    return;
  }
  const int angle = options_.session.angle_deg;
  const int res = options_.session.resolution_centideg;
  const size_t expected_count = static_cast<size_t>(angle * 100 / res + 1);
  if (scan.values.ranges.size() != expected_count) {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.malformed_scans++;
    stats_.last_error = "dropped a scan with " + std::to_string(scan.values.ranges.size()) +
                        " values (expected " + std::to_string(expected_count) +
                        "): the sensor's variant differs from the configuration";
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.sensor_status = scan.values.status;
    stats_.have_status = true;
    if (statusSeverity(scan.values.status) >= StatusSeverity::kError) {
      stats_.status_rejected++;
      stats_.last_error = "dropped a scan: sensor reports " + describeStatus(scan.values.status);
      return;
    }
  }
  // First-beam time: the last byte arrived (bytes_fed - end_position) byte
  // times before the read returned; the telegram took its length in byte
  // times to send, and the sweep preceded it.
  const int baud = session_->currentBaud();
  const double byte_time = lineTime(1, baud);
  const double last_byte_time =
      read_time - static_cast<double>(bytes_fed - event.end_position) * byte_time;
  const size_t telegram_bytes = event.telegram.data.size() + 1 + kTelegramOverhead;
  scan.sweep_time = sweepTime(angle, res);
  scan.time_increment = beamTimeIncrement(angle, res);
  const double raw_stamp = last_byte_time - telegram_bytes * byte_time - scan.sweep_time;
  scan.first_beam_time =
      (options_.filter_stamps ? stamp_filter_.filter(raw_stamp) : raw_stamp) + options_.time_offset;
  scan.angle_deg = angle;
  scan.resolution_centideg = res;
  scan.baud = baud;
  last_scan_ = Clock::now();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.scans++;
  }
  on_scan_(scan);
}

void ScannerLink::shutdown() {
  if (port_.isOpen() && session_) session_->stopStreaming();
  port_.close();
  session_.reset();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.state = LinkState::kDisconnected;
}

}  // namespace sick_lms200
