// libFuzzer target: StepReader::OpenText and Next() (tools/io/step_reader.h); a first byte below 8
// makes the next two choose max_line_bytes and max_step_m.
// The properties are in tests/fuzz/fuzz_checks.h.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  grove::testing::TrapIfViolated(grove::testing::CheckStepReader(data, size));
  return 0;
}
