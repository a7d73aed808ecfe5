// The emulator against the initialisation and streaming sequences of two
// independent LMS200 clients, MRPT's CSickLaserSerial and sicktoolbox's
// SickLMS2xx (with its ROS node sicklms), on a real pseudo-terminal. The
// requests are written out byte for byte as those clients send them; the
// replies are checked at the byte offsets the clients read, which are the
// offsets of the LMS2xx telegram listing. Each client's reply timeouts are
// the windows the emulator must answer in.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "serial_io/serial_port.h"
#include "sick_lms200_driver/emulator/lms200_emulator.h"
#include "sick_lms200_driver/protocol/crc.h"
#include "sick_lms200_driver/protocol/measured_values.h"
#include "sick_lms200_driver/test/emulator_on_pty.h"

namespace sick_lms200 {
namespace {

using Bytes = std::vector<uint8_t>;
using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

// Requests, complete on the wire (STX, address 0, LEN, CMD, data, CRC), and
// the client functions that send them.
// 0x20 0x25, request mode (stops continuous output): MRPT
// LMS_endContinuousMode and the end of LMS_sendMeasuringMode_cm_mm;
// sicktoolbox _setSickOpModeMonitorRequestValues.
const Bytes kStopContinuous{0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08};
// 0x31, status: MRPT LMS_statusQuery; sicktoolbox _getSickStatus.
const Bytes kStatusRequest{0x02, 0x00, 0x01, 0x00, 0x31, 0x15, 0x12};
// 0x20 0x40, 38400 baud: MRPT LMS_setupBaudrate(38400); sicktoolbox
// _setSessionBaud(SICK_BAUD_38400).
const Bytes kSwitchTo38400{0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08};
// 0x20 0x00 "SICK_LMS", installation mode: MRPT LMS_sendMeasuringMode_cm_mm;
// sicktoolbox _setSickOpModeInstallation.
const Bytes kInstallationMode{0x02, 0x00, 0x0A, 0x00, 0x20, 0x00, 0x53, 0x49,
                              0x43, 0x4B, 0x5F, 0x4C, 0x4D, 0x53, 0xBE, 0xC5};
// 0x74, read configuration: MRPT LMS_sendMeasuringMode_cm_mm; sicktoolbox
// _getSickConfig.
const Bytes kReadConfiguration{0x02, 0x00, 0x01, 0x00, 0x74, 0x50, 0x12};
// 0x3B 180 50, variant 180°/0.5°: MRPT LMS_startContinuousMode (FOV 180,
// resolution 50); sicktoolbox SetSickVariant(SICK_SCAN_ANGLE_180,
// SICK_SCAN_RESOLUTION_50).
const Bytes kVariant180HalfDegree{0x02, 0x00, 0x05, 0x00, 0x3B, 0xB4, 0x00, 0x32, 0x00, 0x3B, 0x1F};
// 0x20 0x24, continuous output of complete scans: MRPT LMS_startContinuousMode.
const Bytes kStartContinuous{0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08};
// 0x32, pending errors: sicktoolbox _getSickErrors, called by _testSickBaud.
const Bytes kErrorsRequest{0x02, 0x00, 0x01, 0x00, 0x32, 0x16, 0x12};
// 0x3A, type string: sicktoolbox _getSickType.
const Bytes kTypeRequest{0x02, 0x00, 0x01, 0x00, 0x3A, 0x1E, 0x12};
// 0x20 0x2A, continuous partial scans: sicktoolbox
// _setSickOpModeMonitorStreamValuesFromPartialScan.
const Bytes kStartPartialScans{0x02, 0x00, 0x02, 0x00, 0x20, 0x2A, 0x3A, 0x08};
// 0x77 + 34 bytes, write configuration: MRPT LMS_sendMeasuringMode_cm_mm
// sends back the 34 bytes it read with byte 5 (measuring mode) and 6
// (units) set; sicktoolbox _setSickConfig serialises the configuration it
// parsed with the new units. From the emulator's configuration (all bytes 0
// but the units) both come to all 0 with units cm, or units 1 for mm.
Bytes configurationWrite(bool millimetres) {
  Bytes bytes(4 + 35 + 2, 0x00);
  bytes[0] = 0x02;
  bytes[2] = 0x23;
  bytes[4] = 0x77;
  bytes[4 + 1 + 6] = millimetres ? 0x01 : 0x00;
  bytes[39] = millimetres ? 0x6E : 0x3E;
  bytes[40] = millimetres ? 0xB3 : 0x83;
  return bytes;
}

uint16_t word(const Bytes& bytes, size_t offset) {
  return static_cast<uint16_t>(bytes[offset] | (bytes[offset + 1] << 8));
}

// What came back for one request: the ACK/NAK byte and the reply telegram.
struct Answer {
  bool ack = false;
  bool nak = false;
  double ack_after = -1.0;  // s after the request was written
  Bytes frame;              // STX through CRC; empty when none arrived in time
  // LEN-counted part, the clients' "payload": [0] command, then data, last the status byte.
  Bytes payload() const {
    return frame.size() < 7 ? Bytes{} : Bytes(frame.begin() + 4, frame.end() - 2);
  }
};

// The host side as these clients drive it: raw bytes out, raw bytes in,
// with their timeouts.
class RawClient {
 public:
  RawClient(const std::string& device, int baud) {
    EXPECT_TRUE(port_.open(device, baud)) << port_.error();
  }

  // tcsetattr + tcflush, as both clients change the host's rate.
  void setBaud(int baud) {
    ASSERT_TRUE(port_.setBaud(baud)) << port_.error();
    flush();
  }
  void flush() {
    port_.flush();
    pending_.clear();
  }

  // Writes `request`; waits up to `ack_window` for ACK/NAK and up to
  // `reply_window` (both from the write) for a complete, checksum-valid
  // reply telegram from the sensor.
  Answer exchange(const Bytes& request, milliseconds ack_window, milliseconds reply_window) {
    Answer answer;
    const auto sent = Clock::now();
    EXPECT_EQ(port_.write(request.data(), request.size()), serial_io::IoStatus::kOk);
    const auto ack_deadline = sent + ack_window;
    const auto reply_deadline = sent + reply_window;
    while (true) {
      uint8_t byte = 0;
      const auto deadline = answer.ack || answer.nak ? reply_deadline : ack_deadline;
      if (!readByte(deadline, &byte)) return answer;
      if (byte == 0x06 || byte == 0x15) {
        answer.ack = byte == 0x06;
        answer.nak = byte == 0x15;
        answer.ack_after = std::chrono::duration<double>(Clock::now() - sent).count();
        if (answer.nak) return answer;
        continue;
      }
      if (byte == 0x02) {
        pending_.insert(pending_.begin(), byte);
        answer.frame = readFrame(reply_deadline);
        return answer;
      }
    }
  }

  // The next telegram from the sensor (STX, 0x80, LEN, ..., valid CRC), as
  // a client hunting for STX then the address reads it; empty at the deadline.
  Bytes readFrame(Clock::time_point deadline) {
    Bytes frame;
    uint8_t byte = 0;
    while (readByte(deadline, &byte)) {
      if (frame.empty() && byte != 0x02) continue;
      if (frame.size() == 1 && byte != 0x80) {
        frame.clear();
        if (byte == 0x02) frame.push_back(byte);
        continue;
      }
      frame.push_back(byte);
      if (frame.size() < 4) continue;
      const size_t total = 4 + word(frame, 2) + 2;
      if (frame.size() < total) continue;
      const uint16_t crc = lmsCrc16(frame.data(), total - 2);
      if (word(frame, total - 2) == crc) return frame;
      ADD_FAILURE() << "telegram with a bad checksum";
      frame.clear();
    }
    return {};
  }
  Bytes readFrame(milliseconds timeout) { return readFrame(Clock::now() + timeout); }

 private:
  bool readByte(Clock::time_point deadline, uint8_t* byte) {
    while (pending_.empty()) {
      const auto now = Clock::now();
      if (now >= deadline) return false;
      uint8_t buffer[512];
      const auto left = std::chrono::duration_cast<milliseconds>(deadline - now);
      const auto result = port_.read(buffer, sizeof(buffer), std::max(left, milliseconds(1)));
      if (result.status == serial_io::IoStatus::kClosed) return false;
      pending_.insert(pending_.end(), buffer, buffer + result.bytes);
    }
    *byte = pending_.front();
    pending_.erase(pending_.begin());
    return true;
  }

  serial_io::SerialPort port_;
  Bytes pending_;
};

void sleepFor(milliseconds wait) { std::this_thread::sleep_for(wait); }

// A copy of the truth of the scan the emulator sent with these raw range
// values (`scale` metres per unit), if there is one.
std::optional<TrueScan> findTruth(const std::vector<TrueScan>& truths,
                                  const std::vector<uint16_t>& raw, double scale) {
  for (const TrueScan& truth : truths) {
    if (truth.sent.size() != raw.size()) continue;
    bool same = true;
    for (size_t i = 0; i < raw.size() && same; ++i) {
      same = std::isinf(truth.sent[i]) ? raw[i] >= kFirstReservedCode
                                       : std::abs(truth.sent[i] - raw[i] * scale) < 1e-6;
    }
    if (same) return truth;
  }
  return std::nullopt;
}

// Ranges of a measured-values payload ([0] command, [1..2] info word), as
// the clients mask them for measuring mode 0: the low 13 bits.
std::vector<uint16_t> rawRanges(const Bytes& payload, int count) {
  std::vector<uint16_t> raw(count);
  for (int i = 0; i < count; ++i) raw[i] = word(payload, 3 + 2 * i) & 0x1FFF;
  return raw;
}

// ---------------------------------------------------------------------------
// MRPT, libs/hwdrivers/src/CSickLaserSerial.cpp, with the class defaults:
// COM_baudRate 38400, FOV 180, resolution 50 (0.01°), mm_mode off (cm).
// SendCommandToSICK writes, sleeps 15 ms and waits 50 ms for the ACK;
// LMS_waitIncomingFrame(timeout) then reads the reply byte by byte.
// ---------------------------------------------------------------------------
TEST(MrptCSickLaserSerial, FindsTheSensorAt9600SwitchesTo38400AndReadsFiveScans) {
  test::EmulatorOnPty emulator(EmulatorOptions{}, "/tmp/lms200_emulator_test_mrpt");
  RawClient lms(emulator.device(), 9600);  // tryToOpenComms: COM->setConfig(9600)
  const milliseconds ack_window(15 + 50);
  auto within = [](int timeout_ms) { return milliseconds(15 + timeout_ms); };

  // LMS_setupSerialComms, first the desired rate (38400): the sensor is at
  // 9600 and must not answer LMS_endContinuousMode nor LMS_statusQuery.
  lms.setBaud(38400);
  EXPECT_FALSE(lms.exchange(kStopContinuous, ack_window, within(50)).ack);
  sleepFor(milliseconds(100));
  lms.flush();
  EXPECT_FALSE(lms.exchange(kStatusRequest, ack_window, within(500)).ack);

  // Then 9600: LMS_endContinuousMode, purgeBuffers, LMS_statusQuery.
  lms.setBaud(9600);
  Answer answer = lms.exchange(kStopContinuous, ack_window, within(50));
  EXPECT_TRUE(answer.ack);
  sleepFor(milliseconds(100));
  lms.flush();
  answer = lms.exchange(kStatusRequest, ack_window, within(500));
  ASSERT_TRUE(answer.ack) << "LMS_statusQuery at 9600: no ACK";
  ASSERT_FALSE(answer.frame.empty()) << "LMS_statusQuery at 9600: no reply within 500 ms";
  EXPECT_EQ(answer.frame[4], 0xB1);

  // LMS_setupBaudrate(38400), then its check of the reply: LEN 3, 0xA0 and
  // the status byte 0x10 at frame[6]. MRPT stays at 9600 if any differs.
  answer = lms.exchange(kSwitchTo38400, ack_window, within(500));
  ASSERT_TRUE(answer.ack);
  ASSERT_EQ(answer.frame.size(), 4u + 3u + 2u);
  EXPECT_EQ(answer.frame[2], 0x03);
  EXPECT_EQ(answer.frame[4], 0xA0);
  EXPECT_EQ(answer.frame[5], 0x00) << "mode change accepted";
  EXPECT_EQ(answer.frame[6], 0x10) << "status byte: no error, LMS type 6";
  lms.setBaud(38400);
  sleepFor(milliseconds(500));
  answer = lms.exchange(kStatusRequest, ack_window, within(500));
  ASSERT_TRUE(answer.ack) << "LMS_statusQuery at 38400: no ACK";
  ASSERT_FALSE(answer.frame.empty());
  emulator.locked([](Lms200Emulator& e, auto&) {
    EXPECT_EQ(e.baud(), 38400);
    return 0;
  });

  // LMS_sendMeasuringMode_cm_mm: installation mode, read the configuration,
  // write it back with byte 5 (measuring mode) and 6 (units) set for cm,
  // then request mode.
  answer = lms.exchange(kInstallationMode, ack_window, within(500));
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.frame[4], 0xA0);
  EXPECT_EQ(answer.frame[5], 0x00);
  answer = lms.exchange(kReadConfiguration, ack_window, within(500));
  ASSERT_EQ(answer.frame.size(), 4u + 1u + 34u + 1u + 2u);
  EXPECT_EQ(answer.frame[4], 0xF4);
  // MRPT's write: the received telegram's bytes 5..38 behind a new header,
  // [10] and [11] replaced, a new CRC.
  Bytes write(answer.frame.begin(), answer.frame.begin() + 39);
  write[10] = 0x00;  // mm_mode off: measuring mode 0
  write[11] = 0x00;  // and units cm
  write[1] = 0x00;
  write[2] = 0x23;
  write[3] = 0x00;
  write[4] = 0x77;
  const uint16_t crc = lmsCrc16(write.data(), write.size());
  write.push_back(static_cast<uint8_t>(crc & 0xFF));
  write.push_back(static_cast<uint8_t>(crc >> 8));
  EXPECT_EQ(write, configurationWrite(false));
  answer = lms.exchange(write, ack_window, within(600));
  ASSERT_FALSE(answer.frame.empty()) << "no reply to 0x77 within MRPT's 600 ms";
  EXPECT_EQ(answer.frame[4], 0xF7);
  EXPECT_EQ(answer.frame[5], 0x01);
  answer = lms.exchange(kStopContinuous, ack_window, within(500));
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.frame[4], 0xA0);
  EXPECT_EQ(answer.frame[5], 0x00);

  // LMS_startContinuousMode: variant 180°/0.5°, then continuous output.
  answer = lms.exchange(kVariant180HalfDegree, ack_window, within(500));
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.frame[5], 0x01) << "variant accepted";
  answer = lms.exchange(kStartContinuous, ack_window, within(500));
  ASSERT_FALSE(answer.frame.empty());

  // waitContinuousSampleFrame: STX, 0x80, LEN + 6 <= 800, command 0xB0,
  // count = info & 0x1FF, units = info >> 14, status = frame[LEN + 6 - 3].
  for (int scan = 0; scan < 5; ++scan) {
    const Bytes frame = lms.readFrame(milliseconds(1000));
    ASSERT_FALSE(frame.empty()) << "scan " << scan << " of 5 missing";
    ASSERT_EQ(frame[4], 0xB0);
    ASSERT_LE(frame.size(), 800u);
    const uint16_t info = word(frame, 5);
    ASSERT_EQ(info & 0x01FF, 361);
    EXPECT_EQ((info & 0xC000) >> 14, 0) << "cm, as MRPT configured";
    EXPECT_EQ(frame[frame.size() - 3], 0x10);
    const std::vector<uint16_t> raw = rawRanges(Bytes(frame.begin() + 4, frame.end() - 2), 361);
    const std::optional<TrueScan> truth = emulator.locked(
        [&](Lms200Emulator&, const std::vector<TrueScan>& t) { return findTruth(t, raw, 0.01); });
    EXPECT_TRUE(truth.has_value()) << "scan " << scan << " is not one the emulator measured";
  }
}

// ---------------------------------------------------------------------------
// sicktoolbox, c++/drivers/lms2xx/sicklms2xx/SickLMS2xx.cc: Initialize(38400)
// as the ROS node sicklms (sicktoolbox_wrapper) calls it, then its setup for
// the parameters angle 180, resolution 0.5, units mm, then GetSickPartialScan
// (what sicklms reads for 180° scans). _sendMessageAndGetReply flushes the
// terminal, sends, and waits 1 s for the reply (3 s for mode changes, 15 s
// for a configuration write). `payload` indices below are sicktoolbox's:
// [0] is the reply's command byte.
// ---------------------------------------------------------------------------
constexpr milliseconds kAckWindow(60);  // the LMS acknowledges within 60 ms
constexpr milliseconds kMessageTimeout(1000);
constexpr milliseconds kSwitchModeTimeout(3000);
constexpr milliseconds kConfigTimeout(15000);

// _getSickStatus's reads of the 0xB1 reply, checked against the sensor's state.
void expectStatusReply(const Answer& answer, uint8_t operating_mode, int resolution_centideg,
                       uint8_t units) {
  const Bytes payload = answer.payload();
  ASSERT_EQ(payload.size(), 1u + 152u + 1u) << "0xB1: command, 152 data bytes, status";
  EXPECT_EQ(word(answer.frame, 2), 154) << "LEN";
  EXPECT_EQ(payload[0], 0xB1);
  EXPECT_EQ(std::string(payload.begin() + 1, payload.begin() + 8), "V02.10 ") << "software";
  EXPECT_EQ(payload[8], operating_mode) << "operating mode";
  EXPECT_EQ(payload[9], 0x00) << "status: ok";
  EXPECT_EQ(payload[18], 0x00) << "variant type: LMS2xx type 6";
  EXPECT_EQ(payload[102], 0x00) << "measuring mode: 8 m / 80 m, fields A, B, dazzle";
  EXPECT_EQ(word(payload, 107), 180) << "scan angle";
  EXPECT_EQ(word(payload, 109), resolution_centideg) << "resolution";
  EXPECT_EQ(payload[122], units) << "measured value units";
  EXPECT_EQ(std::string(payload.begin() + 124, payload.begin() + 131), "S01.31 ") << "boot PROM";
  EXPECT_EQ(payload.back(), 0x10) << "status byte";
}

TEST(SicktoolboxSickLMS2xx, InitialisesSetsHalfDegreeAndStreamsPartialScans) {
  test::EmulatorOnPty emulator(EmulatorOptions{}, "/tmp/lms200_emulator_test_stb_a");
  // _setupConnection: the terminal at DEFAULT_SICK_LMS_2XX_SICK_BAUD, 9600.
  RawClient lms(emulator.device(), 9600);

  // _setSessionBaud(SICK_BAUD_38400): any 0xA0 reply, then the terminal to
  // 38400 and a 250 ms sleep.
  Answer answer = lms.exchange(kSwitchTo38400, kAckWindow, kMessageTimeout);
  EXPECT_TRUE(answer.ack);
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.payload()[0], 0xA0);
  lms.setBaud(38400);
  sleepFor(milliseconds(250));

  // _setSickOpModeMonitorRequestValues: payload[1] must be 0.
  answer = lms.exchange(kStopContinuous, kAckWindow, kSwitchModeTimeout);
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.payload()[1], 0x00);

  // _getSickType: the string between payload[1] and the status byte.
  answer = lms.exchange(kTypeRequest, kAckWindow, kMessageTimeout);
  ASSERT_FALSE(answer.frame.empty());
  Bytes payload = answer.payload();
  const std::string type(payload.begin() + 1, payload.end() - 1);
  EXPECT_NE(type.find("LMS200;30106"), std::string::npos) << type;

  // _getSickStatus.
  answer = lms.exchange(kStatusRequest, kAckWindow, kMessageTimeout);
  ASSERT_FALSE(answer.frame.empty());
  expectStatusReply(answer, 0x25, 100, 0x01);

  // _getSickConfig: _parseSickConfigProfile(&payload[1]): [5] measuring
  // mode, [6] units.
  answer = lms.exchange(kReadConfiguration, kAckWindow, kMessageTimeout);
  payload = answer.payload();
  ASSERT_EQ(payload.size(), 1u + 34u + 1u);
  EXPECT_EQ(payload[1 + 5], 0x00);
  EXPECT_EQ(payload[1 + 6], 0x01) << "mm";

  // sicklms: resolution 0.5 differs from the 1.0 reported, so
  // SetSickVariant(180, 0.5): payload[1] == 1, angle and resolution echoed.
  answer = lms.exchange(kVariant180HalfDegree, kAckWindow, kMessageTimeout);
  payload = answer.payload();
  ASSERT_GE(payload.size(), 6u);
  EXPECT_EQ(payload[1], 0x01);
  EXPECT_EQ(word(payload, 2), 180);
  EXPECT_EQ(word(payload, 4), 50);
  // Units mm already: no configuration write. GetSickStatus now reports 0.5°.
  answer = lms.exchange(kStatusRequest, kAckWindow, kMessageTimeout);
  ASSERT_FALSE(answer.frame.empty());
  expectStatusReply(answer, 0x25, 50, 0x01);

  // GetSickPartialScan: _setSickOpModeMonitorStreamValuesFromPartialScan,
  // then 0xB0 telegrams parsed by _parseSickScanProfileB0: count =
  // src[0] + 256 * (src[1] & 0x03), partial index = (src[1] & 0x18) >> 3 in
  // 0.25° steps (sicklms adds 0.25° × index to the angles).
  answer = lms.exchange(kStartPartialScans, kAckWindow, kSwitchModeTimeout);
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.payload()[1], 0x00) << "partial-scan mode accepted";
  emulator.locked([](Lms200Emulator& e, auto&) {
    EXPECT_TRUE(e.streamingPartialScans());
    EXPECT_EQ(e.operatingMode(), 0x2A);
    return 0;
  });
  int previous_index = -1;
  int seen[4] = {0, 0, 0, 0};
  for (int scan = 0; scan < 8; ++scan) {
    const Bytes frame = lms.readFrame(kMessageTimeout);
    ASSERT_FALSE(frame.empty()) << "partial scan " << scan << " missing";
    payload = Bytes(frame.begin() + 4, frame.end() - 2);
    ASSERT_EQ(payload[0], 0xB0);
    const uint8_t* src = &payload[1];
    const int count = src[0] + 256 * (src[1] & 0x03);
    const int index = (src[1] & 0x18) >> 3;
    EXPECT_TRUE(src[1] & 0x20) << "bit 13: a partial scan";
    EXPECT_EQ(src[1] >> 6, 1) << "mm";
    ASSERT_TRUE(index == 0 || index == 2) << index;
    EXPECT_EQ(count, index == 0 ? 181 : 180);
    ASSERT_EQ(payload.size(), 1u + 2u + 2u * count + 1u);
    EXPECT_EQ(payload.back(), 0x10);
    EXPECT_EQ(index, previous_index == 0 ? 2 : 0) << "partials alternate, 0° first";
    previous_index = index;
    seen[index]++;
    const std::vector<uint16_t> raw = rawRanges(payload, count);
    const std::optional<TrueScan> truth = emulator.locked(
        [&](Lms200Emulator&, const std::vector<TrueScan>& t) { return findTruth(t, raw, 0.001); });
    ASSERT_TRUE(truth.has_value())
        << "partial scan " << scan << " is not one the emulator measured";
    EXPECT_TRUE(truth->partial);
    EXPECT_EQ(truth->partial_offset_centideg, index * 25);
  }
  EXPECT_EQ(seen[0], 4);
  EXPECT_EQ(seen[2], 4);
}

// A sensor left at 38400 by an earlier run, in cm: sicktoolbox's switch at
// 9600 times out, it finds the rate with _testSickBaud (request 0x32) and
// then writes the units. 500 kbaud is not probed: a pty cannot be set to it.
TEST(SicktoolboxSickLMS2xx, DetectsTheBaudWithRequest0x32AndChangesUnitsToMm) {
  EmulatorOptions options;
  options.initial_baud = 38400;
  options.units = Units::kCentimetres;
  options.config_write_delay = 0.5;
  test::EmulatorOnPty emulator(options, "/tmp/lms200_emulator_test_stb_b");
  RawClient lms(emulator.device(), 9600);

  // _setSessionBaud(SICK_BAUD_38400) at 9600: the sensor hears noise.
  Answer answer = lms.exchange(kSwitchTo38400, kAckWindow, milliseconds(300));
  EXPECT_FALSE(answer.ack);
  EXPECT_TRUE(answer.frame.empty());
  // _testSickBaud(SICK_BAUD_19200) (9600 is skipped: it is the default):
  // _getSickErrors at 19200, no reply.
  lms.setBaud(19200);
  answer = lms.exchange(kErrorsRequest, kAckWindow, milliseconds(300));
  EXPECT_TRUE(answer.frame.empty());
  // _testSickBaud(SICK_BAUD_38400): _getSickErrors answered. Errors are
  // (payload length - 2) / 2 pairs: none.
  lms.setBaud(38400);
  answer = lms.exchange(kErrorsRequest, kAckWindow, kMessageTimeout);
  EXPECT_TRUE(answer.ack);
  {
    const Bytes payload = answer.payload();
    ASSERT_EQ(payload.size(), 2u);
    EXPECT_EQ(payload[0], 0xB2);
    EXPECT_EQ(payload[1], 0x10) << "status byte";
  }
  // The rate found is the one asked for: no second _setSessionBaud.

  answer = lms.exchange(kStopContinuous, kAckWindow, kSwitchModeTimeout);
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.payload()[1], 0x00);
  answer = lms.exchange(kTypeRequest, kAckWindow, kMessageTimeout);
  ASSERT_FALSE(answer.frame.empty());
  answer = lms.exchange(kStatusRequest, kAckWindow, kMessageTimeout);
  ASSERT_FALSE(answer.frame.empty());
  expectStatusReply(answer, 0x25, 100, 0x00);
  EXPECT_EQ(word(answer.payload(), 116), 0x8019) << "baud rate: 38400";
  answer = lms.exchange(kReadConfiguration, kAckWindow, kMessageTimeout);
  ASSERT_EQ(answer.payload().size(), 1u + 34u + 1u);
  EXPECT_EQ(answer.payload()[1 + 6], 0x00) << "cm";

  // sicklms: units mm differ, SetSickMeasuringUnits(mm) -> _setSickConfig:
  // installation mode, 0x77 with the configuration read and units 1, request
  // mode, status again.
  answer = lms.exchange(kInstallationMode, kAckWindow, kSwitchModeTimeout);
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.payload()[1], 0x00);
  answer = lms.exchange(configurationWrite(true), kAckWindow, kConfigTimeout);
  EXPECT_TRUE(answer.ack);
  Bytes payload = answer.payload();
  ASSERT_EQ(payload.size(), 1u + 1u + 34u + 1u);
  EXPECT_EQ(payload[1], 0x01) << "configuration accepted";
  EXPECT_EQ(payload[2 + 6], 0x01) << "_parseSickConfigProfile(&payload[2]): mm";
  answer = lms.exchange(kStopContinuous, kAckWindow, kSwitchModeTimeout);
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.payload()[1], 0x00);
  answer = lms.exchange(kStatusRequest, kAckWindow, kMessageTimeout);
  ASSERT_FALSE(answer.frame.empty());
  expectStatusReply(answer, 0x25, 100, 0x01);

  // GetSickPartialScan at 1°: every partial scan is a whole 181-value scan
  // with offset 0.
  answer = lms.exchange(kStartPartialScans, kAckWindow, kSwitchModeTimeout);
  ASSERT_FALSE(answer.frame.empty());
  EXPECT_EQ(answer.payload()[1], 0x00);
  for (int scan = 0; scan < 3; ++scan) {
    const Bytes frame = lms.readFrame(kMessageTimeout);
    ASSERT_FALSE(frame.empty()) << "partial scan " << scan << " missing";
    payload = Bytes(frame.begin() + 4, frame.end() - 2);
    ASSERT_EQ(payload[0], 0xB0);
    EXPECT_EQ(payload[1] + 256 * (payload[2] & 0x03), 181);
    EXPECT_EQ((payload[2] & 0x18) >> 3, 0);
    EXPECT_EQ(payload[2] >> 6, 1) << "mm";
  }
}

}  // namespace
}  // namespace sick_lms200
