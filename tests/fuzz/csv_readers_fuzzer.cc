// libFuzzer target: ReadMapCsv, ReadPathCsv (tools/io/output_readers.h), ReadTimedPoints
// (tools/report/trajectory_metrics.h) and FastSLAM's ControlReader and ObservationReader
// (tools/io/fastslam_inputs.h) on the input written to a per-process file under /tmp.
// The properties are in tests/fuzz/fuzz_checks.h.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  grove::testing::TrapIfViolated(grove::testing::CheckCsvReaders(data, size));
  return 0;
}
