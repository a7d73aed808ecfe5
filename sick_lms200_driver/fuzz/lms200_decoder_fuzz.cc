// libFuzzer target: arbitrary bytes, split into arbitrary chunks, through the
// telegram decoder, the measured-values parser and the interlace assembler.
// Built only with -DEKF_SLAM_LMS200_FUZZ=ON and clang; see
// docs/sick_lms200_driver.md for the command.
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sick_lms200_driver/protocol/crc.h"
#include "sick_lms200_driver/protocol/measured_values.h"
#include "sick_lms200_driver/protocol/telegram.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace sick_lms200;
  if (size < 2) return 0;
  // First byte: address and chunking; the rest is the wire.
  const uint8_t control = data[0];
  TelegramDecoder decoder((control & 1) ? kSensorAddress : kHostAddress);
  InterlaceAssembler assembler(control & 2 ? 100 : 180, control & 2 ? 25 : 50);
  const size_t chunk = 1 + (control >> 2);
  const uint8_t* wire = data + 1;
  const size_t wire_size = size - 1;
  for (size_t offset = 0; offset < wire_size; offset += chunk) {
    const size_t n = std::min(chunk, wire_size - offset);
    decoder.feed(wire + offset, n);
    DecoderEvent event;
    while (decoder.next(&event)) {
      assert(event.end_position <= decoder.bytesFed());
      if (event.kind != DecoderEvent::Kind::kTelegram) continue;
      // Every telegram handed out carries a valid checksum.
      const std::vector<uint8_t> bytes =
          encodeTelegram(event.telegram.address, event.telegram.command, event.telegram.data);
      assert(bytes.size() <= kMaxTelegramLength + kTelegramOverhead);
      MeasuredValues values;
      std::string error;
      event.telegram.command = cmd::kMeasuredValues;
      if (parseMeasuredValues(event.telegram, &values, &error)) {
        assert(values.ranges.size() == values.raw.size());
        assert(values.ranges.size() <= static_cast<size_t>(kMaxValueCount));
        std::vector<float> full;
        assembler.add(values, &full);
      } else {
        assert(!error.empty());
      }
    }
  }
  assert(decoder.bufferedBytes() <= kMaxTelegramLength + kTelegramOverhead + chunk);
  return 0;
}
