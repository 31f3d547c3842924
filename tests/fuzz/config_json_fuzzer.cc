// libFuzzer target: ApplyConfigJson and FootSlamConfig::Validate
// (grove/config_json.h).
// The properties are in tests/fuzz/fuzz_checks.h.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  grove::testing::TrapIfViolated(grove::testing::CheckConfigJson(data, size));
  return 0;
}
