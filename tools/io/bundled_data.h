// Where the `grove` command finds its bundled data (Victoria Park, the walk and its truth,
// Bailey's webmap, the scenario maps): $GROVE_DATA_DIR when set, else the directory
// GROVE_DATA_FROM_BINDIR names relative to the running executable. Installed, that is
// <prefix>/share/grove beside <prefix>/bin/grove; in a build tree, a link made by
// tools/CMakeLists.txt to the source tree's tools/data. No absolute path is compiled in, so an
// installed or packaged command reads only what was installed with it.
#ifndef GROVE_TOOLS_IO_BUNDLED_DATA_H_
#define GROVE_TOOLS_IO_BUNDLED_DATA_H_

#include <string>

namespace grove::tools {

// The data directory, with links resolved (the directory need not exist).
std::string BundledDataDir();

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_BUNDLED_DATA_H_
