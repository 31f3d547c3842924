// The `grove fastslam` commands: run (on the generic run loop) and evaluate.
#ifndef GROVE_TOOLS_FASTSLAM_RUN_H_
#define GROVE_TOOLS_FASTSLAM_RUN_H_

#include <string>
#include <vector>

#include "grove/fastslam.h"
#include "tools/run_loop.h"

namespace grove::tools {

struct FastSlamRunOptions {
  RunOptions run;
  std::string controls_path;
  std::string observations_path;
  std::string truth_path;            // optional: truth.csv (t,x,y,heading), scored and drawn
  std::string landmarks_truth_path;  // optional: landmarks_truth.csv (id,x,y), drawn and scored
};

// Runs FastSLAM and writes every output; returns an exit code after printing any error.
int RunFastSlamCommand(const FastSlamConfig& config, const FastSlamRunOptions& options);

// `grove fastslam evaluate`: prints the JSON report to stdout.
int FastSlamEvaluateCommand(const std::string& truth_path, const std::string& trajectory_path,
                            const std::string& landmarks_path,
                            const std::string& landmarks_truth_path);

// `id,x,y,sxx,sxy,syy`, one landmark a row.
std::string LandmarksCsv(const std::vector<LandmarkEstimate>& landmarks);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_FASTSLAM_RUN_H_
