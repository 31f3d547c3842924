// Suggestions for a mistyped word on the command line: the known word nearest by edit distance.
#ifndef GROVE_TOOLS_CLI_DID_YOU_MEAN_H_
#define GROVE_TOOLS_CLI_DID_YOU_MEAN_H_

#include <string>
#include <vector>

namespace grove::tools {

// The word of `known` nearest to `given` ("--particles" for "--particels"), or "" when none is
// close enough to be meant.
std::string DidYouMean(const std::string& given, const std::vector<std::string>& known);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_DID_YOU_MEAN_H_
