// Bounded randomised run of the fuzz body in `make test`: random bytes, and
// valid packets with random damage, through decoder, parsers and emulator.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "p3dx_driver/fuzz/fuzz_one_input.h"
#include "p3dx_driver/protocol/commands.h"
#include "p3dx_driver/protocol/packet.h"
#include "p3dx_driver/protocol/sip.h"

namespace p3dx {
namespace {

TEST(FuzzOneInput, RandomBytesAndDamagedPacketsNeverCrash) {
  std::mt19937 random(2024);
  for (int iteration = 0; iteration < 20000; ++iteration) {
    std::vector<uint8_t> input(1, static_cast<uint8_t>(random()));
    const int pieces = 1 + random() % 8;
    for (int piece = 0; piece < pieces; ++piece) {
      std::vector<uint8_t> bytes;
      switch (random() % 4) {
        case 0: {
          StandardSip sip;
          sip.x_ticks = static_cast<uint16_t>(random());
          sip.sonars.resize(random() % 20);
          bytes = encodePacket(encodeStandardSip(sip));
          break;
        }
        case 1:
          bytes = encodePacket(encodeCommand(static_cast<Command>(random() % 60),
                                             static_cast<int>(random() % 5000) - 2500));
          break;
        default:
          bytes.resize(random() % 40);
          for (uint8_t& byte : bytes) byte = static_cast<uint8_t>(random());
      }
      if (!bytes.empty() && random() % 3 == 0) bytes[random() % bytes.size()] ^= 0xFF;
      input.insert(input.end(), bytes.begin(), bytes.end());
    }
    fuzzOneInput(input.data(), input.size());
  }
  SUCCEED();
}

}  // namespace
}  // namespace p3dx
