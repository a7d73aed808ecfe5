// libFuzzer entry point (built with -DEKF_SLAM_FUZZ=ON and clang):
//   p3dx_packet_fuzzer -max_total_time=60
#include <cstddef>
#include <cstdint>

#include "p3dx_driver/fuzz/fuzz_one_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  p3dx::fuzzOneInput(data, size);
  return 0;
}
