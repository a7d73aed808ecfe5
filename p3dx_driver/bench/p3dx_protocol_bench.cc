// Throughput of the driver's receive path: bytes → packets → SIP → pose.
//   make bench   (writes output/bench/p3dx_protocol_bench.json)
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "p3dx_driver/protocol/packet.h"
#include "p3dx_driver/protocol/sip.h"

namespace p3dx {
namespace {

// A stream of `count` standard SIPs with 16 sonar readings, as the robot
// sends them, optionally with every 20th packet corrupted.
std::vector<uint8_t> sipStream(int count, bool corrupt) {
  std::vector<uint8_t> stream;
  for (int i = 0; i < count; ++i) {
    StandardSip sip;
    sip.x_ticks = static_cast<uint16_t>(i * 37);
    sip.theta_units = static_cast<int16_t>(i % 4096 - 2048);
    for (uint8_t s = 0; s < 16; ++s) sip.sonars.push_back({s, static_cast<uint16_t>(1000 + s)});
    sip.has_io = sip.has_battery_x10 = sip.has_extended = true;
    std::vector<uint8_t> packet = encodePacket(encodeStandardSip(sip));
    if (corrupt && i % 20 == 0) packet.back() ^= 0x5A;
    stream.insert(stream.end(), packet.begin(), packet.end());
  }
  return stream;
}

void decodeAndTrack(benchmark::State& state, bool corrupt) {
  const std::vector<uint8_t> stream = sipStream(1000, corrupt);
  const DriveConversions conversions;
  for (auto _ : state) {
    PacketDecoder decoder;
    PositionTracker tracker;
    std::vector<std::vector<uint8_t>> payloads;
    // Feed in 64-byte reads, like a serial port delivers them.
    for (size_t offset = 0; offset < stream.size(); offset += 64) {
      decoder.feed(stream.data() + offset, std::min<size_t>(64, stream.size() - offset), &payloads);
    }
    double sum = 0.0;
    for (const auto& payload : payloads) {
      StandardSip sip;
      if (parseStandardSip(payload.data(), payload.size(), &sip) == SipError::kNone) {
        sum += tracker.update(sip, conversions).x;
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * stream.size()));
  state.SetItemsProcessed(state.iterations() * 1000);  // SIPs
}

void BM_DecodeParseTrackSips(benchmark::State& state) { decodeAndTrack(state, false); }
void BM_DecodeParseTrackSipsWithCorruption(benchmark::State& state) { decodeAndTrack(state, true); }

BENCHMARK(BM_DecodeParseTrackSips);
BENCHMARK(BM_DecodeParseTrackSipsWithCorruption);

}  // namespace
}  // namespace p3dx

BENCHMARK_MAIN();
