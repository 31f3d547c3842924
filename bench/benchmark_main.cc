// Main for grove's Google Benchmark programs: records what the numbers depend on (commit,
// compiler, build type, allocator, pooling) in the report context and warns when the build is
// not one to measure (LevelDB's db_bench does the same).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "alloc/node_pool.h"
#include "grove/version.h"

int main(int argc, char** argv) {
  const grove::VersionInfo version = grove::Version();
  benchmark::AddCustomContext("grove_version", version.version);
  benchmark::AddCustomContext("grove_commit", version.commit);
  benchmark::AddCustomContext("compiler", version.compiler);
  benchmark::AddCustomContext("build_type", version.build_type);
  benchmark::AddCustomContext("simd", version.simd_target + " of " + version.simd_targets);
  benchmark::AddCustomContext("allocator", "jemalloc (linked into this executable)");
  benchmark::AddCustomContext("node_pool", grove::NodePool::kPooling ? "on" : "off");
#ifndef NDEBUG
  std::fprintf(stderr,
               "WARNING: assertions are on (not an NDEBUG build): timings are not "
               "representative\n");
  benchmark::AddCustomContext("warning", "assertions on");
#endif
#if !defined(__OPTIMIZE__)
  std::fprintf(stderr, "WARNING: the build is not optimised\n");
#endif
  if (!grove::NodePool::kPooling) {
    std::fprintf(stderr, "WARNING: node pooling is off (GROVE_NODE_POOL=OFF)\n");
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
