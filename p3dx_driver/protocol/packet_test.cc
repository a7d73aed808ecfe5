#include "p3dx_driver/protocol/packet.h"

#include <gtest/gtest.h>

#include <random>

#include "p3dx_driver/protocol/commands.h"

namespace p3dx {
namespace {

using Bytes = std::vector<uint8_t>;

// The three vectors of PROTOCOLS.md §1, computed from the algorithm.
TEST(Packet, EncodesTheDocumentedTestVectors) {
  EXPECT_EQ(encodePacket(encodeCommand(Command::kPulse)),
            (Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00}));
  EXPECT_EQ(encodePacket(encodeCommand(Command::kEnable, 1)),
            (Bytes{0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x01, 0x00, 0x05, 0x3B}));
  EXPECT_EQ(encodePacket(encodeCommand(Command::kVel, -200)),
            (Bytes{0xFA, 0xFB, 0x06, 0x0B, 0x1B, 0xC8, 0x00, 0xD3, 0x1B}));
}

TEST(Packet, ChecksumOfEvenLengthSumsBigEndianPairs) {
  const Bytes payload = {0x12, 0x34, 0xFF, 0xFF};
  // 0x1234 + 0xFFFF = 0x11233, kept to 16 bits.
  EXPECT_EQ(checksum(payload.data(), payload.size()), 0x1233);
}

TEST(Packet, ChecksumOfOddLengthXorsTheLastByteIntoTheLowByte) {
  const Bytes payload = {0x12, 0x34, 0x0F};
  EXPECT_EQ(checksum(payload.data(), payload.size()), 0x1234 ^ 0x0F);
  const Bytes single = {0xA5};
  EXPECT_EQ(checksum(single.data(), single.size()), 0x00A5);
}

TEST(PacketDecoder, DeliversPacketsSplitAcrossFeeds) {
  const Bytes packet = encodePacket({0x32, 1, 2, 3, 4, 5});
  PacketDecoder decoder;
  std::vector<Bytes> out;
  for (uint8_t byte : packet) decoder.feed(&byte, 1, &out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (Bytes{0x32, 1, 2, 3, 4, 5}));
  EXPECT_EQ(decoder.stats().packets, 1u);
}

TEST(PacketDecoder, ResynchronisesAfterGarbageAndCountsBadChecksums) {
  Bytes stream = {0x00, 0xFA, 0x13, 0xFB, 0xFA};  // garbage, including a lone 0xFA
  Bytes corrupt = encodePacket({0x33, 9, 9});
  corrupt.back() ^= 0x01;
  stream.insert(stream.end(), corrupt.begin(), corrupt.end());
  const Bytes good = encodePacket({0x32, 7});
  stream.insert(stream.end(), good.begin(), good.end());
  PacketDecoder decoder;
  std::vector<Bytes> out;
  decoder.feed(stream.data(), stream.size(), &out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (Bytes{0x32, 7}));
  EXPECT_EQ(decoder.stats().checksum_errors, 1u);
  EXPECT_GT(decoder.stats().discarded_bytes, 4u);
}

TEST(PacketDecoder, FindsAPacketHiddenBehindAFakeHeader) {
  // A false header whose LEN swallows the real packet: the real one must
  // still be found after the false frame fails its checksum.
  Bytes stream = {0xFA, 0xFB, 0x0C};
  const Bytes good = encodePacket({0x32, 1, 2, 3});
  stream.insert(stream.end(), good.begin(), good.end());
  stream.insert(stream.end(), {0, 0, 0, 0});
  PacketDecoder decoder;
  std::vector<Bytes> out;
  decoder.feed(stream.data(), stream.size(), &out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (Bytes{0x32, 1, 2, 3}));
}

TEST(PacketDecoder, RejectsImpossibleLengths) {
  PacketDecoder decoder;
  std::vector<Bytes> out;
  const Bytes too_short = {0xFA, 0xFB, 0x02, 0x00, 0x00};
  decoder.feed(too_short.data(), too_short.size(), &out);
  const Bytes too_long = {0xFA, 0xFB, 0xFF};
  decoder.feed(too_long.data(), too_long.size(), &out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(decoder.stats().length_errors, 2u);
  EXPECT_LT(decoder.buffered(), 3u);  // never waits for 255 bytes of a bad frame
}

TEST(PacketDecoder, LargestPacketRoundTrips) {
  Bytes payload(kMaxPayloadBytes, 0x5A);
  payload[0] = 0x32;
  const Bytes packet = encodePacket(payload);
  EXPECT_EQ(packet.size(), kMaxPacketBytes);
  PacketDecoder decoder;
  std::vector<Bytes> out;
  decoder.feed(packet.data(), packet.size(), &out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], payload);
}

// Bounded randomised run (the libFuzzer target explores further): random
// noise mixed with valid packets never crashes, never loses a valid packet
// that is not overlapped by noise, and the buffer stays bounded.
TEST(PacketDecoder, RandomNoiseWithValidPacketsIsHandled) {
  std::mt19937 random(12345);
  PacketDecoder decoder;
  size_t sent = 0, received = 0;
  for (int round = 0; round < 20000; ++round) {
    Bytes chunk;
    if (random() % 3 == 0) {
      chunk.resize(random() % 64);
      for (uint8_t& byte : chunk) byte = static_cast<uint8_t>(random() % 4 == 0 ? 0xFA : random());
    } else {
      Bytes payload(1 + random() % 60);
      for (uint8_t& byte : payload) byte = static_cast<uint8_t>(random());
      chunk = encodePacket(payload);
      ++sent;
    }
    std::vector<Bytes> out;
    decoder.feed(chunk.data(), chunk.size(), &out);
    received += out.size();
    ASSERT_LE(decoder.buffered(), kMaxPacketBytes + 64);
  }
  // Noise may swallow the start of a following packet; most survive.
  EXPECT_GT(received, sent * 8 / 10);
  EXPECT_GT(decoder.stats().checksum_errors + decoder.stats().length_errors, 0u);
}

}  // namespace
}  // namespace p3dx
