#include "p3dx_driver/emulator/p3dx_emulator.h"

#include <algorithm>
#include <cmath>

#include "p3dx_driver/protocol/commands.h"
#include "serial_io/pseudo_terminal.h"

namespace p3dx {
namespace {

using ekf_slam::Pose2;

// Moves `value` toward `target` by at most `rate_up` (speeding up) or
// `rate_down` (slowing down) times dt.
double approach(double value, double target, double rate_up, double rate_down, double dt) {
  const bool speeding_up = std::abs(target) > std::abs(value) && target * value >= 0.0;
  const double step = (speeding_up ? rate_up : rate_down) * dt;
  if (std::abs(target - value) <= step) return target;
  return value + (target > value ? step : -step);
}

// The pose increment of an arc of length `distance` turning by `turn`.
Pose2 arc(double distance, double turn) {
  return Pose2(distance * std::cos(turn / 2.0), distance * std::sin(turn / 2.0), turn);
}

constexpr double kDegToRad = ekf_slam::kPi / 180.0;
constexpr double kMaxSubstep = 0.01;          // s
constexpr double kContactRelease = 0.01;      // m moved since a contact that frees the bumper
constexpr double kContactReleaseTurn = 0.35;  // rad (20 degrees) turned since it

}  // namespace

P3dxEmulator::P3dxEmulator(serial_io::ByteStream* stream, EmulatorOptions options)
    : stream_(stream), options_(std::move(options)), random_(options_.seed) {
  conversions_ = conversionsForSubclass(options_.subclass).value_or(DriveConversions{});
  if (options_.stale_session) state_ = State::kOpen;
}

void P3dxEmulator::dropConnection() {
  state_ = State::kWaitSync0;
  target_velocity_ = target_rotational_velocity_ = 0.0;
  wheel_mode_ = false;
  decoder_.clear();
}

void P3dxEmulator::step(double now) {
  if (last_step_ < 0.0) {
    last_step_ = now;
    last_command_ = now;
    next_sip_ = now;
  }
  // Input: a device at another line speed sees only garbage, so ignore it.
  uint8_t buffer[256];
  const auto* pty = dynamic_cast<const serial_io::PseudoTerminal*>(stream_);
  baud_matches_ = options_.baud == 0 || pty == nullptr || pty->peerBaud() == 0 ||
                  pty->peerBaud() == options_.baud;
  for (int reads = 0; reads < 64; ++reads) {
    const serial_io::ReadResult result =
        stream_->read(buffer, sizeof(buffer), std::chrono::milliseconds(0));
    if (result.status != serial_io::IoStatus::kOk) break;
    if (!baud_matches_) continue;
    std::vector<std::vector<uint8_t>> payloads;
    const uint64_t errors_before =
        decoder_.stats().checksum_errors + decoder_.stats().length_errors;
    decoder_.feed(buffer, result.bytes, &payloads);
    stats_.bad_packets +=
        decoder_.stats().checksum_errors + decoder_.stats().length_errors - errors_before;
    for (const auto& payload : payloads) handlePayload(payload, now);
  }

  if (state_ == State::kOpen && !watchdog_tripped_ && now - last_command_ > options_.watchdog) {
    watchdog_tripped_ = true;
    ++stats_.watchdog_trips;
    target_velocity_ = target_rotational_velocity_ = 0.0;
    wheel_mode_ = false;
  }

  double dt = std::max(0.0, now - last_step_);  // time going backwards: no motion
  last_step_ = std::max(last_step_, now);
  // A wheel stall is reported when an increment of this step was blocked.
  if (dt > 1e-9) blocked_ = false;
  while (dt > 1e-9) {
    const double slice = std::min(dt, kMaxSubstep);
    integrate(slice);
    dt -= slice;
    stalled_now_ = blocked_;
    front_bumped_now_ = contact_front_;
    rear_bumped_now_ = contact_rear_;
  }

  if (state_ == State::kOpen && now >= next_sip_) {
    sendSip();
    next_sip_ += options_.sip_period;
    if (next_sip_ < now) next_sip_ = now + options_.sip_period;
  }
}

void P3dxEmulator::integrate(double dt) {
  const double track = conversions_.axleTrackMm() * 1e-3;
  double target_v = target_velocity_;
  double target_w = target_rotational_velocity_;
  if (wheel_mode_) {
    target_v = (target_left_ + target_right_) / 2.0;
    target_w = (target_right_ - target_left_) / track;
  }
  if (!motors_enabled_) {
    velocity_ = rotational_velocity_ = 0.0;
    return;
  }
  target_v = std::clamp(target_v, -options_.max_velocity, options_.max_velocity);
  target_w =
      std::clamp(target_w, -options_.max_rotational_velocity, options_.max_rotational_velocity);
  velocity_ = approach(velocity_, target_v, options_.acceleration, options_.deceleration, dt);
  rotational_velocity_ = approach(rotational_velocity_, target_w, options_.rotational_acceleration,
                                  options_.rotational_acceleration, dt);

  const double distance = velocity_ * dt;
  const double turn = rotational_velocity_ * dt;
  if (distance == 0.0 && turn == 0.0) return;
  const Pose2 proposed = ekf_slam::compose(true_pose_, arc(distance, turn));
  if (options_.faults.stalled) {
    blocked_ = true;
    return;  // the wheels do not turn: neither the pose nor the encoders change
  }
  // Against a wall the wheels stall and the bumper ring on the side the
  // robot drove to is pressed. It stays pressed (the wall stays) until the
  // robot backs away from it, or has moved 1 cm or turned 20 degrees since.
  if (motion_hook_ && !motion_hook_(true_pose_, proposed)) {
    blocked_ = true;
    if (distance > 0.0) contact_front_ = true;
    if (distance < 0.0) contact_rear_ = true;
    travel_since_contact_ = turn_since_contact_ = 0.0;
    return;
  }
  true_pose_ = proposed;
  travel_since_contact_ += std::abs(distance);
  turn_since_contact_ += std::abs(turn);
  if (distance < 0.0) contact_front_ = false;
  if (distance > 0.0) contact_rear_ = false;
  if (travel_since_contact_ > kContactRelease || turn_since_contact_ > kContactReleaseTurn) {
    contact_front_ = contact_rear_ = false;
  }

  double left = distance - turn * track / 2.0;
  double right = distance + turn * track / 2.0;
  if (options_.wheel_noise > 0.0) {
    std::normal_distribution<double> noise(0.0, options_.wheel_noise);
    left *= 1.0 + noise(random_);
    right *= 1.0 + noise(random_);
  }
  odometry_pose_ =
      ekf_slam::compose(odometry_pose_, arc((left + right) / 2.0, (right - left) / track));
}

void P3dxEmulator::handlePayload(const std::vector<uint8_t>& payload, double now) {
  const std::optional<DecodedCommand> command = decodeCommand(payload);
  if (!command) {
    ++stats_.bad_packets;
    return;
  }
  const uint8_t number = command->number;
  switch (state_) {
    case State::kWaitSync0:
      if (number == 0) {
        sendPayload({0});
        state_ = State::kWaitSync1;
      }
      return;
    case State::kWaitSync1:
      if (number == 1) {
        sendPayload({1});
        state_ = State::kWaitSync2;
      } else if (number == 0) {
        sendPayload({0});
      } else {
        state_ = State::kWaitSync0;
      }
      return;
    case State::kWaitSync2:
    case State::kSynced:
      if (state_ == State::kWaitSync2 && number == 2) {
        std::vector<uint8_t> reply = {2};
        for (const std::string& field :
             {options_.name, std::string("Pioneer"), options_.subclass}) {
          reply.insert(reply.end(), field.begin(), field.end());
          reply.push_back(0);
        }
        sendPayload(reply);
        state_ = State::kSynced;
      } else if (state_ == State::kSynced && number == static_cast<uint8_t>(Command::kOpen)) {
        openSession(now);
      } else if (number == 0) {
        sendPayload({0});
        state_ = State::kWaitSync1;
      } else {
        state_ = State::kWaitSync0;
      }
      return;
    case State::kOpen:
      handleCommand(number, command->has_int, command->value, command->raw_value, now);
      return;
  }
}

void P3dxEmulator::openSession(double now) {
  state_ = State::kOpen;
  ++stats_.sessions_opened;
  odometry_pose_ = Pose2();
  motors_enabled_ = false;  // the real controller starts with motors off
  target_velocity_ = target_rotational_velocity_ = 0.0;
  wheel_mode_ = false;
  last_command_ = now;
  watchdog_tripped_ = false;
  next_sip_ = now;
}

void P3dxEmulator::handleCommand(uint8_t number, bool has_int, int value, uint16_t raw,
                                 double now) {
  ++stats_.commands;
  last_command_ = now;
  watchdog_tripped_ = false;
  switch (static_cast<Command>(number)) {
    case Command::kPulse:
    case Command::kOpen:
      break;
    case Command::kClose:
      dropConnection();
      motors_enabled_ = false;
      velocity_ = rotational_velocity_ = 0.0;
      break;
    case Command::kEnable:
      if (has_int) motors_enabled_ = value != 0;
      break;
    case Command::kSetA:
      if (has_int && value > 0) options_.acceleration = value * 1e-3;
      if (has_int && value < 0) options_.deceleration = -value * 1e-3;
      break;
    case Command::kSetV:
      if (has_int && value > 0) options_.max_velocity = std::min(value * 1e-3, 2.2);
      break;
    case Command::kSetO:
      odometry_pose_ = Pose2();
      break;
    case Command::kSetRv:
      if (has_int && value > 0) {
        options_.max_rotational_velocity = std::min(value, 500) * kDegToRad;
      }
      break;
    case Command::kVel:
      if (has_int) {
        target_velocity_ = value * 1e-3;
        wheel_mode_ = false;
      }
      break;
    case Command::kRvel:
      if (has_int) {
        target_rotational_velocity_ = value * kDegToRad;
        wheel_mode_ = false;
      }
      break;
    case Command::kSetRa:
      if (has_int && value > 0) options_.rotational_acceleration = value * kDegToRad;
      break;
    case Command::kSonar:
      if (has_int) sonar_enabled_ = value != 0;
      break;
    case Command::kStop:
      target_velocity_ = target_rotational_velocity_ = 0.0;
      wheel_mode_ = false;
      break;
    case Command::kVel2:
      if (has_int) {
        int left = 0, right = 0;
        decodeVel2(raw, &left, &right);
        target_left_ = left * 1e-3;
        target_right_ = right * 1e-3;
        wheel_mode_ = true;
      }
      break;
    case Command::kEStop:
      target_velocity_ = target_rotational_velocity_ = 0.0;
      velocity_ = rotational_velocity_ = 0.0;
      wheel_mode_ = false;
      break;
    case Command::kHostBaud:
      if (has_int) {
        static constexpr int kRates[] = {9600, 19200, 38400, 57600, 115200};
        if (value >= 0 && value < 5) options_.baud = kRates[value];
      }
      break;
    default:
      break;  // CONFIG, BUMPSTALL and others: accepted, no effect here
  }
}

void P3dxEmulator::sendPayload(const std::vector<uint8_t>& payload) {
  writeBytes(encodePacket(payload));
}

void P3dxEmulator::writeBytes(std::vector<uint8_t> bytes) {
  // At the wrong line speed the client sees only noise.
  if (!baud_matches_) {
    for (uint8_t& byte : bytes) byte = static_cast<uint8_t>(random_() & 0x7F);
  }
  stream_->write(bytes.data(), bytes.size());
}

void P3dxEmulator::sendSip() {
  StandardSip sip;
  const double track_mm = conversions_.axleTrackMm();
  const bool moving = velocity_ != 0.0 || rotational_velocity_ != 0.0;
  sip.type = moving ? kSipMoving : kSipStopped;
  const double mm_per_tick = conversions_.distance_mm_per_tick;
  sip.x_ticks = wrapPositionTicks(std::lround(odometry_pose_.x * 1e3 / mm_per_tick));
  sip.y_ticks = wrapPositionTicks(std::lround(odometry_pose_.y * 1e3 / mm_per_tick));
  sip.theta_units =
      static_cast<int16_t>(std::lround(odometry_pose_.theta / conversions_.angle_rad_per_unit));
  const double v_mm = stalled_now_ ? 0.0 : velocity_ * 1e3;
  const double w_mm = stalled_now_ ? 0.0 : rotational_velocity_ * track_mm / 2.0;
  sip.left_velocity = static_cast<int16_t>(std::lround(v_mm - w_mm));
  sip.right_velocity = static_cast<int16_t>(std::lround(v_mm + w_mm));
  sip.battery_decivolts = static_cast<uint8_t>(std::lround(options_.battery_volts * 10.0));
  // Stall bits 0 (left) and 8 (right); the five segments of each bumper
  // ring at bits 1-5 (rear) and 9-13 (front).
  sip.stall_bump =
      static_cast<uint16_t>((stalled_now_ ? 0x0101 : 0) | (front_bumped_now_ ? 0x1F << 9 : 0) |
                            (rear_bumped_now_ ? 0x1F << 1 : 0));
  sip.flags = (motors_enabled_ ? 0x0001 : 0) | (sonar_enabled_ ? 0x001E : 0);
  if (sonar_enabled_) {
    for (uint8_t i = 0; i < 16; ++i) sip.sonars.push_back({i, 5000});
  }
  sip.has_io = sip.has_battery_x10 = sip.has_extended = true;
  sip.battery_x10 = static_cast<uint16_t>(std::lround(options_.battery_volts * 100.0));
  sip.rotational_velocity =
      static_cast<int16_t>(std::lround(rotational_velocity_ / kDegToRad * 10));

  std::vector<uint8_t> packet = encodePacket(encodeStandardSip(sip));
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const EmulatorFaults& faults = options_.faults;
  if (faults.corrupt_rate > 0.0 && uniform(random_) < faults.corrupt_rate) {
    packet.back() ^= 0x5A;
    ++stats_.sips_corrupted;
  }
  if (faults.drop_rate > 0.0 && uniform(random_) < faults.drop_rate) {
    packet.erase(packet.begin() + 3 + static_cast<long>(random_() % (packet.size() - 3)));
    ++stats_.sips_corrupted;
  }
  if (faults.garbage_rate > 0.0 && uniform(random_) < faults.garbage_rate) {
    std::vector<uint8_t> garbage(1 + random_() % 8);
    for (uint8_t& byte : garbage) byte = static_cast<uint8_t>(random_());
    packet.insert(packet.begin(), garbage.begin(), garbage.end());
  }
  writeBytes(std::move(packet));
  ++stats_.sips_sent;
}

}  // namespace p3dx
