// libFuzzer target: the host's session state machine (baud probing, mode
// changes, variant, configuration read/write, continuous output) against a
// "device" that answers every request with arbitrary bytes. Each reply is a
// chunk of the input; when the input runs out the device is unplugged.
// Properties: initialize() ends (no hang, no crash, no UB), reports an error
// exactly when it fails, and never writes a request that is not a valid
// telegram from the host.
// Built by `make fuzz` (clang, -DEKF_SLAM_FUZZ=ON).
#include <fuzzer/FuzzedDataProvider.h>

#include <cassert>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "serial_io/byte_stream.h"
#include "sick_lms200_driver/protocol/session.h"
#include "sick_lms200_driver/protocol/telegram.h"

namespace {

using namespace sick_lms200;

// A device whose bytes come from the fuzzer's input, one chunk per read.
class ScriptedDevice : public serial_io::ByteStream {
 public:
  explicit ScriptedDevice(FuzzedDataProvider& input) : input_(input) {}

  serial_io::ReadResult read(uint8_t* buffer, size_t size, std::chrono::milliseconds) override {
    serial_io::ReadResult result;
    if (input_.remaining_bytes() == 0) {
      result.status = serial_io::IoStatus::kClosed;  // out of input: unplugged
      return result;
    }
    const size_t wanted = input_.ConsumeIntegralInRange<size_t>(0, size);
    const std::vector<uint8_t> bytes = input_.ConsumeBytes<uint8_t>(wanted);
    std::copy(bytes.begin(), bytes.end(), buffer);
    result.bytes = bytes.size();
    // A chunk of nothing is a timeout; reads never wait here.
    result.status = bytes.empty() ? serial_io::IoStatus::kTimeout : serial_io::IoStatus::kOk;
    return result;
  }

  serial_io::IoStatus write(const uint8_t* data, size_t size) override {
    // Every request is one complete host telegram with a valid checksum.
    TelegramDecoder decoder(kHostAddress);
    decoder.feed(data, size);
    DecoderEvent event;
    assert(decoder.next(&event) && event.kind == DecoderEvent::Kind::kTelegram);
    assert(event.end_position == size);
    ++writes_;
    return writes_ > kMaxWrites ? serial_io::IoStatus::kClosed : serial_io::IoStatus::kOk;
  }

  bool isOpen() const override { return true; }
  void close() override {}
  std::string name() const override { return "fuzz-device"; }

 private:
  // The session's request count is bounded by its options (attempts per
  // request, probe rates); this only guards against a loop.
  static constexpr int kMaxWrites = 1000;
  FuzzedDataProvider& input_;
  int writes_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider input(data, size);
  SessionOptions options;
  const int bauds[] = {9600, 19200, 38400, 500000};
  options.baud = bauds[input.ConsumeIntegralInRange<int>(0, 3)];
  options.angle_deg = input.ConsumeBool() ? 180 : 100;
  const int resolutions[] = {100, 50, 25};
  options.resolution_centideg = resolutions[input.ConsumeIntegralInRange<int>(0, 2)];
  options.units = input.ConsumeBool() ? Units::kMillimetres : Units::kCentimetres;
  options.attempts = input.ConsumeIntegralInRange<int>(1, 3);
  const uint8_t settable = input.ConsumeIntegral<uint8_t>();  // which host rates exist

  ScriptedDevice device(input);
  TelegramDecoder decoder(kSensorAddress);
  Session session(
      device,
      [&](int baud) {
        for (int i = 0; i < 4; ++i) {
          if (bauds[i] == baud) return ((settable >> i) & 1) != 0;
        }
        return false;
      },
      decoder, options);
  session.setPause([](std::chrono::milliseconds) {});
  const bool ok = session.initialize();
  assert(ok == session.error().empty());
  if (ok) {
    assert(session.currentBaud() == options.baud);
    session.stopStreaming();
  }
  return 0;
}
