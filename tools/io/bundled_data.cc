#include "tools/io/bundled_data.h"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace grove::tools {

std::string BundledDataDir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("GROVE_DATA_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path dir = (ec ? fs::path(".") : exe.parent_path()) / GROVE_DATA_FROM_BINDIR;
  const fs::path resolved = fs::weakly_canonical(dir, ec);
  return (ec ? dir : resolved).string();
}

}  // namespace grove::tools
