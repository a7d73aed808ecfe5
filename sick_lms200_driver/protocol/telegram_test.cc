#include "sick_lms200_driver/protocol/telegram.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "sick_lms200_driver/protocol/crc.h"

namespace sick_lms200 {
namespace {

using Bytes = std::vector<uint8_t>;

uint16_t crcOfVector(const Bytes& telegram) {
  return lmsCrc16(telegram.data(), telegram.size() - 2);
}
uint16_t trailingCrc(const Bytes& telegram) {
  return telegram[telegram.size() - 2] | (telegram.back() << 8);
}

std::vector<DecoderEvent> decodeAll(TelegramDecoder* decoder, const Bytes& bytes) {
  decoder->feed(bytes.data(), bytes.size());
  std::vector<DecoderEvent> events;
  DecoderEvent event;
  while (decoder->next(&event)) events.push_back(event);
  return events;
}

TEST(LmsCrc, MatchesTheThreeProtocolTestVectors) {
  const Bytes installation{0x02, 0x00, 0x0A, 0x00, 0x20, 0x00, 0x53, 0x49,
                           0x43, 0x4B, 0x5F, 0x4C, 0x4D, 0x53, 0xBE, 0xC5};
  const Bytes baud38400{0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08};
  const Bytes continuous{0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08};
  for (const Bytes& vector : {installation, baud38400, continuous}) {
    EXPECT_EQ(crcOfVector(vector), trailingCrc(vector));
  }
  EXPECT_EQ(trailingCrc(installation), 0xC5BE);
}

TEST(LmsCrc, IsNotCrc16Arc) {
  // CRC-16/ARC of "123456789" is 0xBB3D; the LMS variant differs.
  const Bytes digits{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_NE(lmsCrc16(digits.data(), digits.size()), 0xBB3D);
}

TEST(TelegramEncoder, ReproducesTheTestVectorsByteForByte) {
  EXPECT_EQ(encodeTelegram(kHostAddress, cmd::kModeChange, {mode::kBaud38400}),
            (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08}));
  EXPECT_EQ(encodeTelegram(kHostAddress, cmd::kModeChange, {mode::kContinuousAll}),
            (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08}));
  EXPECT_EQ(encodeTelegram(kHostAddress, cmd::kModeChange,
                           {0x00, 'S', 'I', 'C', 'K', '_', 'L', 'M', 'S'}),
            (Bytes{0x02, 0x00, 0x0A, 0x00, 0x20, 0x00, 0x53, 0x49, 0x43, 0x4B, 0x5F, 0x4C, 0x4D,
                   0x53, 0xBE, 0xC5}));
}

TEST(TelegramDecoder, DecodesAckThenReplyAndReportsEndPositions) {
  TelegramDecoder decoder(kSensorAddress);
  Bytes stream{kAck};
  const Bytes reply = encodeTelegram(kSensorAddress, 0xA0, {0x00, 0x10});
  stream.insert(stream.end(), reply.begin(), reply.end());
  stream.push_back(kNak);
  const auto events = decodeAll(&decoder, stream);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].kind, DecoderEvent::Kind::kAck);
  EXPECT_EQ(events[1].kind, DecoderEvent::Kind::kTelegram);
  EXPECT_EQ(events[1].telegram.command, 0xA0);
  EXPECT_EQ(events[1].telegram.data, (Bytes{0x00, 0x10}));
  EXPECT_EQ(events[1].end_position, 1 + reply.size());
  EXPECT_EQ(events[2].kind, DecoderEvent::Kind::kNak);
  EXPECT_EQ(decoder.stats().telegrams, 1u);
}

TEST(TelegramDecoder, WaitsForTruncatedTelegramsAndCompletesThemByteByByte) {
  TelegramDecoder decoder(kSensorAddress);
  const Bytes reply = encodeTelegram(kSensorAddress, 0xBA, Bytes(40, 'x'));
  for (size_t i = 0; i + 1 < reply.size(); ++i) {
    EXPECT_TRUE(decodeAll(&decoder, {reply[i]}).empty()) << "byte " << i;
  }
  const auto events = decodeAll(&decoder, {reply.back()});
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].telegram.data.size(), 40u);
}

TEST(TelegramDecoder, DropsCorruptedTelegramAndFindsTheNextOne) {
  TelegramDecoder decoder(kSensorAddress);
  Bytes bad = encodeTelegram(kSensorAddress, 0xB0, Bytes(20, 0x11));
  bad[10] ^= 0x01;
  const Bytes good = encodeTelegram(kSensorAddress, 0xB1, {0x42});
  Bytes stream = bad;
  stream.insert(stream.end(), good.begin(), good.end());
  std::vector<Telegram> telegrams;
  for (const auto& event : decodeAll(&decoder, stream)) {
    if (event.kind == DecoderEvent::Kind::kTelegram) telegrams.push_back(event.telegram);
  }
  ASSERT_EQ(telegrams.size(), 1u);
  EXPECT_EQ(telegrams[0].command, 0xB1);
  EXPECT_EQ(decoder.stats().crc_errors, 1u);
}

TEST(TelegramDecoder, RejectsOversizedAndZeroLengthsWithoutWaiting) {
  TelegramDecoder decoder(kSensorAddress);
  const size_t too_long = kMaxTelegramLength + 1;
  Bytes stream{kStx,
               kSensorAddress,
               static_cast<uint8_t>(too_long & 0xFF),
               static_cast<uint8_t>(too_long >> 8),
               kStx,
               kSensorAddress,
               0x00,
               0x00};
  const Bytes good = encodeTelegram(kSensorAddress, 0xB1, {0x42});
  stream.insert(stream.end(), good.begin(), good.end());
  const auto events = decodeAll(&decoder, stream);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].telegram.command, 0xB1);
  EXPECT_EQ(decoder.stats().bad_frames, 2u);
}

TEST(TelegramDecoder, IgnoresTelegramsForTheOtherDirection) {
  TelegramDecoder decoder(kSensorAddress);
  const auto events = decodeAll(&decoder, encodeTelegram(kHostAddress, 0x20, {0x24}));
  EXPECT_TRUE(events.empty());
  EXPECT_GE(decoder.stats().bad_frames, 1u);
}

TEST(TelegramDecoder, ResynchronisesAfterGarbageContainingFalseStartBytes) {
  TelegramDecoder decoder(kSensorAddress);
  Bytes stream{0x55, kStx, 0x13, kStx, kSensorAddress, 0x05, 0x00, 0xFF};
  const Bytes good = encodeTelegram(kSensorAddress, 0xB0, Bytes(8, 0x33));
  stream.insert(stream.end(), good.begin(), good.end());
  stream.insert(stream.end(), good.begin(), good.end());
  const auto events = decodeAll(&decoder, stream);
  int telegrams = 0;
  for (const auto& event : events) telegrams += event.kind == DecoderEvent::Kind::kTelegram;
  EXPECT_EQ(telegrams, 2);
}

TEST(TelegramDecoder, ResetForgetsPartialInputButKeepsPositions) {
  TelegramDecoder decoder(kSensorAddress);
  const Bytes good = encodeTelegram(kSensorAddress, 0xB1, {0x42});
  decodeAll(&decoder, Bytes(good.begin(), good.begin() + 4));
  decoder.reset();
  const auto events = decodeAll(&decoder, good);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].end_position, 4 + good.size());
}

// Randomised property test (bounded, deterministic seeds): valid telegrams
// separated by garbage without STX are all recovered in order, whatever the
// chunking; arbitrary byte soup never yields a telegram with a bad checksum
// and never crashes.
TEST(TelegramDecoderRandomised, RecoversEveryTelegramBetweenGarbage) {
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int trial = 0; trial < 200; ++trial) {
    TelegramDecoder decoder(kSensorAddress);
    Bytes stream;
    std::vector<Bytes> sent;
    const int count = 1 + trial % 7;
    for (int t = 0; t < count; ++t) {
      for (int g = byte(rng) % 12; g > 0; --g) {
        uint8_t b = static_cast<uint8_t>(byte(rng));
        if (b == kStx) b = 0x03;
        stream.push_back(b);
      }
      Bytes data(byte(rng) % 64);
      for (auto& d : data) d = static_cast<uint8_t>(byte(rng));
      sent.push_back(data);
      const Bytes telegram = encodeTelegram(kSensorAddress, 0xB0, data);
      stream.insert(stream.end(), telegram.begin(), telegram.end());
    }
    std::vector<Bytes> received;
    size_t i = 0;
    while (i < stream.size()) {
      const size_t chunk = std::min(stream.size() - i, static_cast<size_t>(1 + byte(rng) % 40));
      for (const auto& event :
           decodeAll(&decoder, Bytes(stream.begin() + i, stream.begin() + i + chunk))) {
        if (event.kind == DecoderEvent::Kind::kTelegram) received.push_back(event.telegram.data);
      }
      i += chunk;
    }
    EXPECT_EQ(received, sent) << "trial " << trial;
  }
}

TEST(TelegramDecoderRandomised, ByteSoupNeverYieldsAnUncheckedTelegram) {
  std::mt19937 rng(777);
  std::uniform_int_distribution<int> byte(0, 255);
  TelegramDecoder decoder(kSensorAddress);
  uint64_t fed = 0;
  Bytes all;
  int telegrams = 0;
  for (int round = 0; round < 2000; ++round) {
    Bytes chunk(1 + byte(rng) % 64);
    for (auto& b : chunk) b = static_cast<uint8_t>(byte(rng) < 40 ? kStx : byte(rng));
    if (round % 3 == 0) chunk[1 % chunk.size()] = kSensorAddress;
    fed += chunk.size();
    all.insert(all.end(), chunk.begin(), chunk.end());
    for (const auto& event : decodeAll(&decoder, chunk)) {
      if (event.kind != DecoderEvent::Kind::kTelegram) continue;
      const Bytes wire =
          encodeTelegram(event.telegram.address, event.telegram.command, event.telegram.data);
      // The telegram is exactly the bytes that were on the wire, checksum included.
      ASSERT_LE(event.end_position, fed);
      ASSERT_GE(event.end_position, wire.size());
      EXPECT_TRUE(
          std::equal(wire.begin(), wire.end(),
                     all.end() - (fed - event.end_position) - static_cast<long>(wire.size())));
      telegrams++;
    }
  }
  EXPECT_EQ(decoder.bytesFed(), fed);
  EXPECT_GT(decoder.stats().discarded_bytes, fed / 2);
  RecordProperty("telegrams_found_in_soup", telegrams);
  EXPECT_LE(decoder.bufferedBytes(), kMaxTelegramLength + kTelegramOverhead);
}

}  // namespace
}  // namespace sick_lms200
