// Runs FootSLAM on a step file (t,dx,dy per line, one header line) under a configuration given
// as JSON (default {"particles": 2000}) and prints the last mean pose, the size of the
// cumulative map and the library's version.
#include <grove/collective.h>
#include <grove/config_json.h>
#include <grove/footslam.h>
#include <grove/version.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: %s STEPS.csv [CONFIG_JSON]\n", argv[0]);
    return 2;
  }
  std::printf("%s\n", grove::VersionString().c_str());
  grove::FootSlamConfig config;
  const std::string json = argc == 3 ? argv[2] : R"({"particles": 2000})";
  if (grove::Status s =
          grove::ApplyConfigJson(grove::FootSlamConfigFields(), "CONFIG_JSON", json, &config);
      !s.ok()) {
    std::fprintf(stderr, "%s\n", s.ToString().c_str());
    return 2;
  }
  // One rank of a collective in this process: the same results as FootSlam::Create(config). With
  // InProcessCollective::Create(K), each endpoint driven by its own thread, the particles would be
  // split over K ranks.
  std::vector<std::unique_ptr<grove::Collective>> ranks = grove::InProcessCollective::Create(1);
  grove::StatusOr<std::unique_ptr<grove::FootSlam>> slam =
      grove::FootSlam::Create(config, ranks[0].get());
  if (!slam.ok()) {
    std::fprintf(stderr, "%s\n", slam.status().ToString().c_str());
    return 1;
  }
  std::ifstream in(argv[1]);
  std::string line;
  std::getline(in, line);  // the header
  for (int row = 2; std::getline(in, line); ++row) {
    std::istringstream fields(line);
    double t, dx, dy;
    char comma1, comma2;
    if (!(fields >> t >> comma1 >> dx >> comma2 >> dy) || comma1 != ',' || comma2 != ',') {
      std::fprintf(stderr, "%s:%d: not t,dx,dy\n", argv[1], row);
      return 1;
    }
    if (grove::Status s = (*slam)->Step(t, dx, dy); !s.ok()) {
      std::fprintf(stderr, "%s:%d: %s\n", argv[1], row, s.ToString().c_str());
      return 1;
    }
  }
  grove::StatusOr<std::vector<grove::HexCounts>> map = (*slam)->CumulativeMap();
  if (!map.ok()) {
    std::fprintf(stderr, "%s\n", map.status().ToString().c_str());
    return 1;
  }
  const grove::Pose2 pose = (*slam)->MeanPose();
  std::printf("%lld steps; mean pose x %.3f m, y %.3f m, heading %.4f rad; %zu hexagons mapped\n",
              static_cast<long long>((*slam)->steps()), pose.x_m, pose.y_m, pose.heading_rad,
              map->size());
  return (*slam)->steps() > 0 && !map->empty() ? 0 : 1;
}
