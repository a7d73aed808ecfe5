// Session and ScannerLink against the emulator on a real pseudo-terminal.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "serial_io/serial_port.h"
#include "sick_lms200_driver/emulator/lms200_emulator.h"
#include "sick_lms200_driver/protocol/scanner_link.h"
#include "sick_lms200_driver/protocol/session.h"
#include "sick_lms200_driver/test/emulator_on_pty.h"

namespace sick_lms200 {
namespace {

using test::EmulatorOnPty;
using test::wallNow;

TEST(Session, InitialisesFrom9600To38400AndStartsStreaming) {
  EmulatorOnPty emulator(EmulatorOptions{}, "/tmp/lms200_session_test_a");
  serial_io::SerialPort port;
  ASSERT_TRUE(port.open(emulator.device(), 9600)) << port.error();
  TelegramDecoder decoder(kSensorAddress);
  SessionOptions options;
  options.baud = 38400;
  Session session(
      port, [&](int baud) { return port.setBaud(baud); }, decoder, options);
  ASSERT_TRUE(session.initialize()) << session.error();
  EXPECT_EQ(session.currentBaud(), 38400);
  EXPECT_EQ(session.typeString().rfind("LMS200", 0), 0u) << session.typeString();
  EXPECT_EQ(port.baud(), 38400);
  emulator.locked([](Lms200Emulator& e, auto&) {
    EXPECT_EQ(e.baud(), 38400);
    EXPECT_TRUE(e.streaming());
    return 0;
  });
  // Streamed scans decode at the new rate.
  int scans = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (scans < 3 && std::chrono::steady_clock::now() < deadline) {
    uint8_t buffer[512];
    const auto result = port.read(buffer, sizeof(buffer), std::chrono::milliseconds(100));
    decoder.feed(buffer, result.bytes);
    DecoderEvent event;
    while (decoder.next(&event)) {
      MeasuredValues values;
      std::string error;
      if (event.kind == DecoderEvent::Kind::kTelegram &&
          parseMeasuredValues(event.telegram, &values, &error)) {
        EXPECT_EQ(values.ranges.size(), 181u);
        scans++;
      }
    }
  }
  EXPECT_EQ(scans, 3);
  EXPECT_TRUE(session.stopStreaming()) << session.error();
}

// An LMS200 ends its replies and scans with status byte 0x10 (no error,
// data source LMS type 6 in bits 3-4); 0x00 has those bits reserved. The
// driver reads only the severity and contamination bits, so it initialises
// and streams with either.
TEST(Session, InitialisesAndStreamsWithStatusByte0x10Or0x00) {
  for (const uint8_t status : {uint8_t{0x10}, uint8_t{0x00}}) {
    EmulatorOptions emulator_options;
    emulator_options.status_byte = status;
    EmulatorOnPty emulator(emulator_options,
                           "/tmp/lms200_session_test_status_" + std::to_string(status));
    serial_io::SerialPort port;
    ASSERT_TRUE(port.open(emulator.device(), 9600)) << port.error();
    TelegramDecoder decoder(kSensorAddress);
    Session session(
        port, [&](int baud) { return port.setBaud(baud); }, decoder, SessionOptions{});
    ASSERT_TRUE(session.initialize()) << session.error();
    EXPECT_EQ(session.sensorStatus(), status);
    MeasuredValues values;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    bool scanned = false;
    while (!scanned && std::chrono::steady_clock::now() < deadline) {
      uint8_t buffer[512];
      const auto result = port.read(buffer, sizeof(buffer), std::chrono::milliseconds(100));
      decoder.feed(buffer, result.bytes);
      DecoderEvent event;
      std::string error;
      while (!scanned && decoder.next(&event)) {
        scanned = event.kind == DecoderEvent::Kind::kTelegram &&
                  parseMeasuredValues(event.telegram, &values, &error);
      }
    }
    ASSERT_TRUE(scanned);
    EXPECT_EQ(values.status, status);
    EXPECT_EQ(statusSeverity(values.status), StatusSeverity::kOk);
  }
}

// A client that times the device: every request, the slow configuration
// write (0x77) included, is acknowledged within 60 ms of its last byte, as
// a real LMS200 does; the write's reply follows once the EEPROM is written
// (config_write_delay). Clients time out waiting for the ACK otherwise.
TEST(Session, AcknowledgesEveryRequestWithin60MsAndAnswersSlowWritesLater) {
  EmulatorOptions options;
  options.config_write_delay = 0.5;
  EmulatorOnPty emulator(options, "/tmp/lms200_session_test_ack");
  serial_io::SerialPort port;
  ASSERT_TRUE(port.open(emulator.device(), 9600)) << port.error();
  TelegramDecoder decoder(kSensorAddress);
  // Sends `request`; the seconds until its ACK and until its reply telegram.
  auto timed = [&](uint8_t command, const std::vector<uint8_t>& data, double* ack, double* reply,
                   Telegram* telegram) {
    const std::vector<uint8_t> bytes = encodeTelegram(kHostAddress, command, data);
    ASSERT_EQ(port.write(bytes.data(), bytes.size()), serial_io::IoStatus::kOk);
    const double sent = wallNow();
    *ack = *reply = -1.0;
    while (*reply < 0.0 && wallNow() - sent < 3.0) {
      uint8_t buffer[256];
      const auto result = port.read(buffer, sizeof(buffer), std::chrono::milliseconds(5));
      decoder.feed(buffer, result.bytes);
      DecoderEvent event;
      while (decoder.next(&event)) {
        if (event.kind == DecoderEvent::Kind::kAck && *ack < 0.0) *ack = wallNow() - sent;
        if (event.kind == DecoderEvent::Kind::kTelegram) {
          *reply = wallNow() - sent;
          *telegram = event.telegram;
        }
      }
    }
  };
  double ack = 0.0, reply = 0.0;
  Telegram answer;
  const std::string password = kInstallationPassword;
  std::vector<uint8_t> installation{mode::kInstallation};
  installation.insert(installation.end(), password.begin(), password.end());
  timed(cmd::kModeChange, installation, &ack, &reply, &answer);
  EXPECT_GE(ack, 0.0);
  EXPECT_LE(ack, 0.060) << "installation mode";
  ASSERT_GE(reply, 0.0);
  timed(cmd::kReadConfig, {}, &ack, &reply, &answer);
  EXPECT_LE(ack, 0.060) << "read configuration";
  ASSERT_GE(reply, 0.0);
  ASSERT_GE(answer.data.size(), kConfigSize);
  const std::vector<uint8_t> config(answer.data.begin(), answer.data.begin() + kConfigSize);
  timed(cmd::kWriteConfig, config, &ack, &reply, &answer);
  EXPECT_GE(ack, 0.0);
  EXPECT_LE(ack, 0.060) << "write configuration: the ACK must not wait for the EEPROM";
  EXPECT_GE(reply, 0.45) << "the reply comes once the configuration is written";
  // 0xF7 as the LMS2xx telegram listing gives it: accepted (1), the
  // configuration the sensor now holds, the status byte.
  ASSERT_EQ(answer.data.size(), 1 + kConfigSize + 1);
  EXPECT_EQ(answer.data[0], 1) << "write accepted";
  EXPECT_EQ(std::vector<uint8_t>(answer.data.begin() + 1, answer.data.begin() + 1 + kConfigSize),
            config);
}

TEST(Session, ProbesAStreamingSensorAndChangesVariantAndUnits) {
  EmulatorOptions emulator_options;
  emulator_options.initial_baud = 19200;  // left at another rate by a previous run
  emulator_options.nak_rate = 0.2;        // and a flaky line: retries needed
  emulator_options.seed = 3;
  EmulatorOnPty emulator(emulator_options, "/tmp/lms200_session_test_b");
  serial_io::SerialPort port;
  ASSERT_TRUE(port.open(emulator.device(), 9600));
  TelegramDecoder decoder(kSensorAddress);
  SessionOptions options;
  options.baud = 38400;
  options.angle_deg = 100;
  options.resolution_centideg = 25;
  options.units = Units::kCentimetres;
  options.attempts = 5;
  Session session(
      port, [&](int baud) { return port.setBaud(baud); }, decoder, options);
  ASSERT_TRUE(session.initialize()) << session.error();
  emulator.locked([](Lms200Emulator& e, auto&) {
    EXPECT_EQ(e.baud(), 38400);
    EXPECT_EQ(e.angleDeg(), 100);
    EXPECT_EQ(e.resolutionCentideg(), 25);
    EXPECT_EQ(e.units(), Units::kCentimetres);
    return 0;
  });
}

// A slow device: the configuration write is acknowledged at once and
// answered only after 3 s. The driver waits for the reply (config_timeout)
// instead of resending the write, and the units change.
TEST(Session, ChangesUnitsOnADeviceThatAnswersTheWriteAfterThreeSeconds) {
  EmulatorOptions emulator_options;
  emulator_options.config_write_delay = 3.0;
  EmulatorOnPty emulator(emulator_options, "/tmp/lms200_session_test_slow");
  serial_io::SerialPort port;
  ASSERT_TRUE(port.open(emulator.device(), 9600));
  TelegramDecoder decoder(kSensorAddress);
  SessionOptions options;
  options.baud = 38400;
  options.units = Units::kCentimetres;
  Session session(
      port, [&](int baud) { return port.setBaud(baud); }, decoder, options);
  ASSERT_TRUE(session.initialize()) << session.error();
  emulator.locked([](Lms200Emulator& e, auto&) {
    EXPECT_EQ(e.units(), Units::kCentimetres);
    EXPECT_TRUE(e.streaming());
    return 0;
  });
}

// initialize() at 9600 against an emulator that never answers, after it
// has sent `first` as if from the sensor (say, a late reply): the
// session's error ("initialised" if it succeeded).
std::string errorAgainstASilentSensor(const std::string& link,
                                      const std::vector<uint8_t>& first = {}) {
  EmulatorOnPty emulator(EmulatorOptions{}, link);
  emulator.locked([](Lms200Emulator& e, auto&) {
    e.setSilent(true);
    return 0;
  });
  serial_io::SerialPort port;
  if (!port.open(emulator.device(), 9600)) return "cannot open the emulator's device";
  if (!first.empty()) emulator.sendAsSensor(first);
  TelegramDecoder decoder(kSensorAddress);
  SessionOptions options;
  options.probe_bauds = {9600, 38400};
  Session session(
      port, [&](int baud) { return port.setBaud(baud); }, decoder, options);
  return session.initialize() ? "initialised" : session.error();
}

TEST(Session, FailsWithAClearMessageWhenNothingAnswers) {
  const std::string error = errorAgainstASilentSensor("/tmp/lms200_session_test_c");
  EXPECT_NE(error.find("no LMS200 answers"), std::string::npos) << error;
}

// A reply that arrives after the host has moved to another rate (late for
// the rate it answered) must not be taken for the sensor's rate: the probe
// confirms with a second request, which a silent sensor leaves unanswered.
TEST(Session, DoesNotTakeALateReplyForTheSensorsRate) {
  std::vector<uint8_t> late{kAck};
  const std::vector<uint8_t> reply = encodeTelegram(
      kSensorAddress, static_cast<uint8_t>(cmd::kModeChange + kReplyOffset), {0x00, 0x10});
  late.insert(late.end(), reply.begin(), reply.end());
  const std::string error = errorAgainstASilentSensor("/tmp/lms200_session_test_late", late);
  EXPECT_NE(error.find("no LMS200 answers"), std::string::npos) << error;
}

TEST(Session, RejectsImpossibleOptionsNamingTheField) {
  SessionOptions options;
  options.angle_deg = 180;
  options.resolution_centideg = 25;
  EXPECT_NE(validateSessionOptions(options).find("resolution"), std::string::npos);
  options = SessionOptions();
  options.baud = 57600;
  EXPECT_NE(validateSessionOptions(options).find("baud"), std::string::npos);
}

TEST(ScannerLink, StampsFirstBeamAndDropsCorruptedScans) {
  EmulatorOptions emulator_options;
  emulator_options.bad_crc_rate = 0.25;
  emulator_options.seed = 11;
  EmulatorOnPty emulator(emulator_options, "/tmp/lms200_session_test_d");
  LinkOptions options;
  options.port = emulator.device();
  std::vector<LaserScanData> scans;
  ScannerLink link(options, wallNow, [&](const LaserScanData& scan) { scans.push_back(scan); });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  while (scans.size() < 30 && std::chrono::steady_clock::now() < deadline) link.spinOnce();
  link.shutdown();
  ASSERT_GE(scans.size(), 30u) << link.stats().last_error;
  const LinkStats stats = link.stats();
  EXPECT_EQ(stats.baud, 38400);
  EXPECT_GE(stats.crc_errors, 1u);

  std::vector<TrueScan> truths = emulator.locked([](Lms200Emulator&, auto& t) { return t; });
  std::vector<double> stamp_errors;
  int corrupted_published = 0;
  for (const LaserScanData& scan : scans) {
    const TrueScan* match = nullptr;
    for (const TrueScan& truth : truths) {
      if (std::abs(truth.first_beam_time - scan.first_beam_time) < 0.02) match = &truth;
    }
    ASSERT_NE(match, nullptr) << "a published scan matches no emulated scan";
    if (match->corrupted) corrupted_published++;
    stamp_errors.push_back(std::abs(match->first_beam_time - scan.first_beam_time));
    for (size_t i = 0; i < scan.values.ranges.size(); ++i) {
      if (std::isinf(match->sent[i])) {
        EXPECT_TRUE(std::isinf(scan.values.ranges[i]));
      } else {
        EXPECT_NEAR(scan.values.ranges[i], match->sent[i], 1e-6);
      }
    }
  }
  EXPECT_EQ(corrupted_published, 0);
  std::sort(stamp_errors.begin(), stamp_errors.end());
  const double median = stamp_errors[stamp_errors.size() / 2];
  const double p90 = stamp_errors[stamp_errors.size() * 9 / 10];
  RecordProperty("stamp_error_median_us", static_cast<int>(median * 1e6));
  RecordProperty("stamp_error_p90_us", static_cast<int>(p90 * 1e6));
  // The median is the driver's accuracy; the tail also carries the host's
  // scheduling (7.1 ms measured during make test beside two busy loops),
  // and must stay within one mirror turn.
  EXPECT_LT(median, 0.002);
  EXPECT_LT(p90, 1.0 / 75.0);
}

}  // namespace
}  // namespace sick_lms200

namespace sick_lms200 {
namespace {

TEST(ScannerLink, ReinitialisesAfterTheSensorFallsSilent) {
  EmulatorOnPty emulator(EmulatorOptions{}, "/tmp/lms200_session_test_e");
  LinkOptions options;
  options.port = emulator.device();
  options.data_timeout = 0.5;
  options.reconnect_delay = 0.2;
  int scans = 0;
  ScannerLink link(options, wallNow, [&](const LaserScanData&) { scans++; });
  auto spinUntil = [&](const std::function<bool()>& done, double seconds) {
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(seconds));
    while (!done() && std::chrono::steady_clock::now() < deadline) link.spinOnce();
    return done();
  };
  ASSERT_TRUE(spinUntil([&] { return scans >= 3; }, 10.0)) << link.stats().last_error;
  emulator.locked([](Lms200Emulator& e, auto&) {
    e.setSilent(true);
    return 0;
  });
  ASSERT_TRUE(spinUntil([&] { return link.stats().link_losses >= 1; }, 5.0));
  EXPECT_NE(link.stats().last_error.find("no valid scan"), std::string::npos)
      << link.stats().last_error;
  emulator.locked([](Lms200Emulator& e, auto&) {
    e.setSilent(false);
    return 0;
  });
  const int before = scans;
  ASSERT_TRUE(spinUntil([&] { return scans >= before + 3; }, 10.0)) << link.stats().last_error;
  EXPECT_GE(link.stats().connects, 2u);
  EXPECT_EQ(link.stats().state, LinkState::kStreaming);
  link.shutdown();
}

}  // namespace
}  // namespace sick_lms200
