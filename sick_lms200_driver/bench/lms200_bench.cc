// Google Benchmark: cost of the LMS200 protocol path per scan (CRC, decode,
// parse) and of the emulator's ray-cast scan generation.
#include <benchmark/benchmark.h>

#include <random>

#include "serial_io/memory_stream.h"
#include "sick_lms200_driver/emulator/lms200_emulator.h"
#include "sick_lms200_driver/emulator/room.h"
#include "sick_lms200_driver/protocol/crc.h"
#include "sick_lms200_driver/protocol/measured_values.h"
#include "sick_lms200_driver/protocol/telegram.h"

namespace sick_lms200 {
namespace {

std::vector<uint8_t> scanTelegram(int count) {
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> range(0, 8182);
  std::vector<uint16_t> raw(count);
  for (auto& r : raw) r = static_cast<uint16_t>(range(rng));
  return encodeTelegram(kSensorAddress, cmd::kMeasuredValues,
                        buildMeasuredValuesData(raw, Units::kMillimetres, 0x10));
}

void BM_Crc16(benchmark::State& state) {
  const std::vector<uint8_t> bytes = scanTelegram(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(lmsCrc16(bytes.data(), bytes.size()));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(bytes.size()));
}
BENCHMARK(BM_Crc16)->Arg(181)->Arg(361)->Arg(721);

// Decode + parse one scan telegram arriving in 64-byte reads.
void BM_DecodeAndParseScan(benchmark::State& state) {
  const std::vector<uint8_t> bytes = scanTelegram(static_cast<int>(state.range(0)));
  TelegramDecoder decoder(kSensorAddress);
  MeasuredValues values;
  std::string error;
  for (auto _ : state) {
    for (size_t i = 0; i < bytes.size(); i += 64) {
      decoder.feed(bytes.data() + i, std::min<size_t>(64, bytes.size() - i));
    }
    DecoderEvent event;
    while (decoder.next(&event)) {
      benchmark::DoNotOptimize(parseMeasuredValues(event.telegram, &values, &error));
    }
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(bytes.size()));
}
BENCHMARK(BM_DecodeAndParseScan)->Arg(181)->Arg(361)->Arg(721);

// Emulator: ray-cast, noise, encode one streamed scan (1° and 0.5°).
void BM_EmulatorScan(benchmark::State& state) {
  const ekf_slam::sim::PolygonWorld world = makeDemoRoom();
  serial_io::MemoryStream stream;
  EmulatorOptions options;
  options.resolution_centideg = static_cast<int>(state.range(0));
  options.initial_baud = 500000;  // the line never limits the scan rate here
  Lms200Emulator emulator(
      stream, world, [](double) { return demoSensorPose(); }, options);
  stream.feed(encodeTelegram(kHostAddress, cmd::kModeChange, {mode::kContinuousAll}));
  double now = 1000.0;
  emulator.spinOnce(now);
  uint64_t scans = 0;
  emulator.setScanObserver([&](const TrueScan&) { scans++; });
  for (auto _ : state) {
    const uint64_t before = scans;
    while (scans == before) {
      now += 0.5 / 75.0;
      emulator.spinOnce(now);
    }
    stream.clearWritten();
  }
  state.counters["scans"] = static_cast<double>(scans);
}
BENCHMARK(BM_EmulatorScan)->Arg(100)->Arg(50);

}  // namespace
}  // namespace sick_lms200

BENCHMARK_MAIN();
