#include "sick_lms200_driver/emulator/lms200_emulator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "sick_lms200_driver/emulator/status_reply.h"
#include "sick_lms200_driver/protocol/scanner_link.h"
#include "sick_lms200_driver/protocol/session.h"

namespace sick_lms200 {

Lms200Emulator::Lms200Emulator(serial_io::ByteStream& stream, const ekf_slam::sim::RayCaster& world,
                               PoseSource pose_source, EmulatorOptions options)
    : stream_(stream),
      world_(world),
      pose_source_(std::move(pose_source)),
      options_(std::move(options)),
      rng_(options_.seed),
      baud_(options_.initial_baud),
      angle_deg_(options_.angle_deg),
      resolution_centideg_(options_.resolution_centideg),
      config_(kConfigSize, 0) {
  config_[kConfigUnitsIndex] = options_.units == Units::kMillimetres ? 1 : 0;
}

Units Lms200Emulator::units() const {
  return config_[kConfigUnitsIndex] == 1 ? Units::kMillimetres : Units::kCentimetres;
}

bool Lms200Emulator::peerMatches() const { return !peer_baud_ || peer_baud_() == baud_; }

void Lms200Emulator::spinOnce(double now) {
  handleInput(now);
  streamScans(now);
  flushOutput(now);
  if (pending_baud_ != 0 && output_.empty() && now >= line_free_at_) {
    baud_ = pending_baud_;
    pending_baud_ = 0;
  }
}

double Lms200Emulator::nextDeadline(double now) const {
  double deadline = std::numeric_limits<double>::infinity();
  if (!output_.empty()) {
    // Batch bytes in 2 ms slices, but wake exactly for the last queued byte
    // (the end of a telegram, whose arrival the driver stamps).
    deadline = std::min(line_free_at_, std::max(output_.front().first, now) + 0.002);
  }
  if (next_sweep_start_ >= 0.0) {
    deadline = std::min(deadline, next_sweep_start_ + currentSweepTime());
  }
  return deadline;
}

double Lms200Emulator::currentSweepTime() const {
  if (streaming_ == Streaming::kPartialScans) return kMirrorPeriod * angle_deg_ / 360.0;
  return sweepTime(angle_deg_, resolution_centideg_);
}

void Lms200Emulator::handleInput(double now) {
  uint8_t buffer[256];
  while (true) {
    const serial_io::ReadResult result =
        stream_.read(buffer, sizeof(buffer), std::chrono::milliseconds(0));
    if (result.status != serial_io::IoStatus::kOk || result.bytes == 0) break;
    if (silent_ || !peerMatches()) {
      garbage_heard_ += result.bytes;  // wrong rate: framing errors, nothing decoded
      continue;
    }
    decoder_.feed(buffer, result.bytes);
  }
  DecoderEvent event;
  while (decoder_.next(&event)) {
    if (event.kind == DecoderEvent::Kind::kTelegram) handleRequest(event.telegram, now);
  }
}

void Lms200Emulator::enqueue(const std::vector<uint8_t>& bytes, double start) {
  double t = std::max(start, line_free_at_);
  for (uint8_t byte : bytes) {
    t += byteTime();
    output_.emplace_back(t, byte);
  }
  line_free_at_ = t;
}

void Lms200Emulator::reply(uint8_t request_command, const std::vector<uint8_t>& data, double start,
                           double work) {
  // The device acknowledges at once (within 60 ms) and answers once the
  // work (an EEPROM write) is done.
  enqueue({kAck}, start);
  enqueue(
      encodeTelegram(kSensorAddress, static_cast<uint8_t>(request_command + kReplyOffset), data),
      start + work);
}

void Lms200Emulator::handleRequest(const Telegram& request, double now) {
  const double start = now + 0.001;  // the sensor's reaction time
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  if (options_.nak_rate > 0.0 && uniform(rng_) < options_.nak_rate) {
    enqueue({kNak}, start);
    return;
  }
  const std::vector<uint8_t>& data = request.data;
  const uint8_t status_byte = options_.status_byte;
  switch (request.command) {
    case cmd::kModeChange: {
      if (data.empty()) break;
      const uint8_t mode_byte = data[0];
      uint8_t result = 0;  // 0 = success
      // Operating modes: what the sensor sends unasked from now on.
      auto stream = [&](Streaming next) {
        streaming_ = next;
        next_sweep_start_ = -1.0;
        next_partial_ = 0;
        installation_mode_ = false;
        operating_mode_ = mode_byte;
      };
      if (mode_byte == mode::kInstallation) {
        const std::string password(data.begin() + 1, data.end());
        if (password == kInstallationPassword) {
          stream(Streaming::kOff);
          installation_mode_ = true;
        } else {
          result = 1;  // wrong password
        }
      } else if (mode_byte == mode::kContinuousAll) {
        stream(Streaming::kCompleteScans);
      } else if (mode_byte == mode::kContinuousPartial) {
        stream(Streaming::kPartialScans);
      } else if (mode_byte == mode::kRequestOnly) {
        stream(Streaming::kOff);
      } else if (baudForModeByte(mode_byte) != 0) {
        pending_baud_ = baudForModeByte(mode_byte);
      } else {
        result = 1;  // not emulated (monitoring, mean values, subranges, ...)
      }
      reply(request.command, {result, status_byte}, start);
      return;
    }
    case cmd::kStatus: {
      std::vector<uint8_t> status = statusReplyData();
      status.push_back(status_byte);
      reply(request.command, status, start);
      return;
    }
    case cmd::kErrors: {
      // Pending errors as (type, number) pairs: none.
      reply(request.command, {status_byte}, start);
      return;
    }
    case cmd::kTypeString: {
      std::vector<uint8_t> type(options_.type_string.begin(), options_.type_string.end());
      type.push_back(status_byte);
      reply(request.command, type, start);
      return;
    }
    case cmd::kVariant: {
      if (data.size() < 4) break;
      const int angle = data[0] | (data[1] << 8);
      const int res = data[2] | (data[3] << 8);
      SessionOptions check;
      check.angle_deg = angle;
      check.resolution_centideg = res;
      const bool ok = validateSessionOptions(check).empty();
      if (ok) {
        angle_deg_ = angle;
        resolution_centideg_ = res;
        next_sweep_start_ = -1.0;
        next_partial_ = 0;
      }
      reply(request.command,
            {static_cast<uint8_t>(ok ? 1 : 0), data[0], data[1], data[2], data[3], status_byte},
            start);
      return;
    }
    case cmd::kReadConfig: {
      std::vector<uint8_t> config = config_;
      config.push_back(status_byte);
      reply(request.command, config, start);
      return;
    }
    case cmd::kWriteConfig: {
      const bool ok =
          installation_mode_ && data.size() == kConfigSize && data[kConfigUnitsIndex] <= 1;
      if (ok) config_ = data;
      // 0xF7: accepted (1) or not (0), then the configuration the sensor
      // now holds, then the status byte.
      std::vector<uint8_t> answer(1 + config_.size() + 1);
      answer.front() = ok ? 1 : 0;
      std::copy(config_.begin(), config_.end(), answer.begin() + 1);
      answer.back() = status_byte;
      reply(request.command, answer, start, ok ? options_.config_write_delay : 0.0);
      return;
    }
    default:
      break;
  }
  enqueue({kNak}, start);  // unknown or malformed request
}

std::vector<uint8_t> Lms200Emulator::statusReplyData() const {
  StatusReport report;
  report.software_version = typeStringField(options_.type_string, 2);
  report.boot_prom_version = typeStringField(options_.type_string, 3);
  report.operating_mode = operating_mode_;
  report.error_pending = statusSeverity(options_.status_byte) >= StatusSeverity::kError;
  report.measuring_mode = config_[kConfigMeasuringModeIndex];
  report.angle_deg = angle_deg_;
  report.resolution_centideg = resolution_centideg_;
  report.restart_mode = config_[kConfigRestartModeIndex];
  report.restart_time = config_[kConfigRestartTimeIndex];
  report.baud = baud_;
  report.units = units();
  return buildStatusData(report);
}

void Lms200Emulator::streamScans(double now) {
  if (streaming_ == Streaming::kOff || silent_) {
    next_sweep_start_ = -1.0;
    return;
  }
  const bool partial = streaming_ == Streaming::kPartialScans;
  const int partials = 100 / resolution_centideg_;
  const double sweep = currentSweepTime();
  if (next_sweep_start_ < 0.0) {
    // The newest sweep that ends once the line is free; sweeps start on
    // mirror-turn boundaries. A complete interlaced scan takes `partials`
    // turns; partial k is measured in turns n with n mod partials = k, and
    // the partials are sent in turn, so that every complete set arrives.
    const double earliest = std::max(now, line_free_at_ - sweep);
    if (partial) {
      int64_t turn = static_cast<int64_t>(std::ceil(earliest / kMirrorPeriod));
      while (turn % partials != next_partial_) ++turn;
      next_sweep_start_ = static_cast<double>(turn) * kMirrorPeriod;
    } else {
      const double cycle = kMirrorPeriod * partials;
      next_sweep_start_ = std::ceil(earliest / cycle) * cycle;
    }
  }
  if (now < next_sweep_start_ + sweep) return;
  if (line_free_at_ > next_sweep_start_ + sweep + 1e-9) {
    next_sweep_start_ = -1.0;  // a reply took the line: measure a newer sweep
    return;
  }
  if (partial) {
    sendPartialScan(next_partial_, next_sweep_start_);
    next_partial_ = (next_partial_ + 1) % partials;
  } else {
    sendScan(next_sweep_start_);
  }
  next_sweep_start_ = -1.0;
}

std::vector<double> Lms200Emulator::castPartial(int k, double turn_start) const {
  ekf_slam::sim::SweepGeometry geometry;
  geometry.angle_min = ekf_slam::degToRad(-angle_deg_ / 2.0 + k * resolution_centideg_ / 100.0);
  geometry.angle_increment = ekf_slam::degToRad(1.0);
  geometry.count = partialBeamCount(angle_deg_, resolution_centideg_, k);
  geometry.max_range = maxRange(units());
  geometry.roll = options_.roll;
  geometry.pitch = options_.pitch;
  return ekf_slam::sim::simulateRanges(world_, pose_source_(turn_start), geometry);
}

void Lms200Emulator::sendScan(double first_beam_time) {
  TrueScan truth;
  truth.first_beam_time = first_beam_time;
  truth.angle_deg = angle_deg_;
  truth.resolution_centideg = resolution_centideg_;
  const int partials = 100 / resolution_centideg_;
  const int count = angle_deg_ * 100 / resolution_centideg_ + 1;
  truth.ranges.assign(count, std::numeric_limits<double>::infinity());
  // Each mirror turn measures one interlaced partial: beams k·res + j·1°.
  for (int k = 0; k < partials; ++k) {
    const std::vector<double> partial = castPartial(k, first_beam_time + k * kMirrorPeriod);
    for (size_t j = 0; j < partial.size(); ++j) truth.ranges[j * partials + k] = partial[j];
  }
  transmit(std::move(truth), -1, first_beam_time + sweepTime(angle_deg_, resolution_centideg_));
}

void Lms200Emulator::sendPartialScan(int k, double first_beam_time) {
  TrueScan truth;
  truth.first_beam_time = first_beam_time;
  truth.angle_deg = angle_deg_;
  truth.resolution_centideg = resolution_centideg_;
  truth.partial = true;
  truth.partial_offset_centideg = k * resolution_centideg_;
  truth.ranges = castPartial(k, first_beam_time);
  transmit(std::move(truth), partialOffsetQuarters(resolution_centideg_, k),
           first_beam_time + currentSweepTime());
}

void Lms200Emulator::transmit(TrueScan truth, int partial_offset_quarters, double send_at) {
  truth.baud = baud_;
  const Units units = this->units();
  const size_t count = truth.ranges.size();
  std::normal_distribution<double> noise(0.0, options_.range_noise_sigma);
  std::vector<uint16_t> raw(count);
  truth.sent.resize(count);
  for (size_t i = 0; i < count; ++i) {
    double measured = truth.ranges[i];
    if (std::isfinite(measured) && options_.range_noise_sigma > 0.0) measured += noise(rng_);
    raw[i] = rawFromRange(measured, units);
    truth.sent[i] = rangeFromRaw(raw[i], units);
  }
  const std::vector<uint8_t> data =
      partial_offset_quarters < 0
          ? buildMeasuredValuesData(raw, units, options_.status_byte)
          : buildPartialScanData(raw, units, partial_offset_quarters, options_.status_byte);
  std::vector<uint8_t> telegram = encodeTelegram(kSensorAddress, cmd::kMeasuredValues, data);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  if (options_.bad_crc_rate > 0.0 && uniform(rng_) < options_.bad_crc_rate) {
    telegram[telegram.size() - 2] ^= 0x5A;
    truth.corrupted = true;
  }
  if (options_.drop_byte_rate > 0.0 && uniform(rng_) < options_.drop_byte_rate) {
    std::uniform_int_distribution<size_t> position(1, telegram.size() - 1);
    telegram.erase(telegram.begin() + static_cast<std::ptrdiff_t>(position(rng_)));
    truth.corrupted = true;
  }
  if (observer_) observer_(truth);
  enqueue(telegram, send_at);
}

void Lms200Emulator::flushOutput(double now) {
  std::vector<uint8_t> due;
  while (!output_.empty() && output_.front().first <= now) {
    due.push_back(output_.front().second);
    output_.pop_front();
  }
  if (due.empty() || silent_) return;
  if (!peerMatches()) {
    // The host samples our bits at another rate: it sees garbage.
    std::uniform_int_distribution<int> byte(0, 255);
    for (uint8_t& b : due) b = static_cast<uint8_t>(byte(rng_));
  }
  stream_.write(due.data(), due.size());
}

}  // namespace sick_lms200
