// What this build of grove is: its version, the commit it was built from, the compiler and the
// SIMD targets compiled in. `grove --version`, every run's summary.json and every benchmark's
// context carry the same.
#ifndef GROVE_VERSION_H_
#define GROVE_VERSION_H_

#include <string>

#include "grove/export.h"

#define GROVE_VERSION_MAJOR 0
#define GROVE_VERSION_MINOR 3
#define GROVE_VERSION_PATCH 0

namespace grove {

struct VersionInfo {
  int major = GROVE_VERSION_MAJOR;
  int minor = GROVE_VERSION_MINOR;
  int patch = GROVE_VERSION_PATCH;
  std::string version;   // "0.3.0"
  std::string commit;    // the short hash built from, "-dirty" with changes ("unknown" outside git)
  std::string compiler;  // "GCC 12.2.0"
  std::string build_type;    // "Release", "Debug", ...
  std::string simd_targets;  // the Highway targets compiled in, best first ("AVX3 AVX2 SSE4 ...")
  std::string simd_target;   // the one this machine runs
};

// The library's version (not the header's: a program linked to a newer libgrove sees its own).
GROVE_EXPORT VersionInfo Version();
// One line: "grove 0.3.0 (commit abc1234, GCC 12.2.0, Release; SIMD: AVX3 of AVX3 AVX2 ...)".
GROVE_EXPORT std::string VersionString();

}  // namespace grove

#endif  // GROVE_VERSION_H_
