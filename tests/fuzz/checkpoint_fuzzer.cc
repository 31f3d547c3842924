// libFuzzer target: FootSlam::Resume on checkpoint files (engine/io/checkpoint_io.h and every
// Load() below it). The properties are in tests/fuzz/fuzz_checks.h.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  grove::testing::TrapIfViolated(grove::testing::CheckCheckpoint(data, size));
  return 0;
}
