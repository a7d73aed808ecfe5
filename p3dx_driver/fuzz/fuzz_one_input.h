// One fuzz iteration over everything that parses robot or client bytes:
// the packet decoder (in chunks chosen by the input), the SIP parser, the
// command decoder and the emulator's command handling. Shared by the
// libFuzzer target and the bounded randomised test in `make test`.
#pragma once

#include <cstddef>
#include <cstdint>

namespace p3dx {

void fuzzOneInput(const uint8_t* data, size_t size);

}  // namespace p3dx
