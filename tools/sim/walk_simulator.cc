#include "tools/sim/walk_simulator.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "tools/sim/sim_random.h"

namespace grove::tools {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Waypoint {
  double x_m;
  double y_m;
  double jitter_m;  // each visit aims at a uniform point within this radius
  std::vector<int> next;
  int door = -1;  // for a point inside a room: the room's door
};

struct WaypointGraph {
  std::vector<Waypoint> nodes;
  int start = 0;         // at (0, 0)
  int first_target = 0;  // east of start, so the walk begins heading 0
  bool explore = false;  // prefer edges not walked yet
};

int AddNode(WaypointGraph* graph, double x_m, double y_m, double jitter_m) {
  graph->nodes.push_back({x_m, y_m, jitter_m, {}});
  return static_cast<int>(graph->nodes.size()) - 1;
}

void Connect(WaypointGraph* graph, int a, int b) {
  graph->nodes[a].next.push_back(b);
  graph->nodes[b].next.push_back(a);
}

// The corridor junctions of a building where others connect to it.
struct BuildingNodes {
  int bottom0, bottom1;  // (0, 0) and (6, 0)
  int left1, right1;     // (0, 6) and (36, 6)
};

// One building with its corner at (ox, oy): corridors 2 m wide on centre lines y = 0 and
// y = 17 (x in [0, 36]), x = 0, 18 and 36. Rooms: 5 south of y = 0, 5 north of y = 17, 8 inside
// the loop off the side and middle corridors. Walls bound x in [-1, 37], y in [-5, 22].
BuildingNodes AddBuilding(WaypointGraph* graph, double ox, double oy) {
  constexpr double kCorridorJitter = 0.4;
  constexpr double kDoorJitter = 0.1;
  constexpr double kRoomJitter = 0.5;
  WaypointGraph& g = *graph;
  int bottom[7];
  int top[7];
  for (int i = 0; i < 7; ++i) bottom[i] = AddNode(&g, ox + 6.0 * i, oy, kCorridorJitter);
  for (int i = 0; i < 7; ++i) top[i] = AddNode(&g, ox + 6.0 * i, oy + 17, kCorridorJitter);
  const int left1 = AddNode(&g, ox, oy + 6, kCorridorJitter);
  const int left2 = AddNode(&g, ox, oy + 11, kCorridorJitter);
  const int right1 = AddNode(&g, ox + 36, oy + 6, kCorridorJitter);
  const int right2 = AddNode(&g, ox + 36, oy + 11, kCorridorJitter);
  const int middle1 = AddNode(&g, ox + 18, oy + 6, kCorridorJitter);
  const int middle2 = AddNode(&g, ox + 18, oy + 11, kCorridorJitter);
  for (int i = 0; i + 1 < 7; ++i) {
    Connect(&g, bottom[i], bottom[i + 1]);
    Connect(&g, top[i], top[i + 1]);
  }
  Connect(&g, bottom[0], left1);
  Connect(&g, left1, left2);
  Connect(&g, left2, top[0]);
  Connect(&g, bottom[6], right1);
  Connect(&g, right1, right2);
  Connect(&g, right2, top[6]);
  Connect(&g, bottom[3], middle1);
  Connect(&g, middle1, middle2);
  Connect(&g, middle2, top[3]);

  // A room: a door in the corridor wall and three interior points, all connected to each other.
  const auto add_room = [&g, ox, oy](int corridor, double door_x, double door_y,
                                     std::initializer_list<std::pair<double, double>> points) {
    const int door = AddNode(&g, ox + door_x, oy + door_y, kDoorJitter);
    Connect(&g, corridor, door);
    std::vector<int> inside = {door};
    for (const auto& [x, y] : points) {
      const int node = AddNode(&g, ox + x, oy + y, kRoomJitter);
      g.nodes[node].door = door;
      for (int other : inside) Connect(&g, node, other);
      inside.push_back(node);
    }
  };
  for (int i = 1; i <= 5; ++i) {
    const double x = 6.0 * i;
    add_room(bottom[i], x, -1, {{x - 1.5, -2.8}, {x + 1.5, -2.8}, {x, -3.8}});
    add_room(top[i], x, 18, {{x - 1.5, 19.8}, {x + 1.5, 19.8}, {x, 20.8}});
  }
  for (const auto& [corridor, y] : {std::pair{middle1, 6.0}, std::pair{middle2, 11.0}}) {
    add_room(corridor, 17, y, {{14.5, y - 1}, {14.5, y + 1.5}, {12, y}});
    add_room(corridor, 19, y, {{21.5, y - 1}, {21.5, y + 1.5}, {24, y}});
  }
  for (const auto& [corridor, y] : {std::pair{left1, 6.0}, std::pair{left2, 11.0}}) {
    add_room(corridor, 1, y, {{3.5, y - 1}, {3.5, y + 1.5}, {6, y}});
  }
  for (const auto& [corridor, y] : {std::pair{right1, 6.0}, std::pair{right2, 11.0}}) {
    add_room(corridor, 35, y, {{32.5, y - 1}, {32.5, y + 1.5}, {30, y}});
  }
  return BuildingNodes{bottom[0], bottom[1], left1, right1};
}

WaypointGraph BuildingGraph() {
  WaypointGraph g;
  const BuildingNodes b = AddBuilding(&g, 0, 0);
  g.start = b.bottom0;
  g.first_target = b.bottom1;
  return g;
}

// kCampusBuildings buildings kCampusSpacing apart along x, each one's east corridor joined to
// the next one's west corridor by an outdoor path at y = 6 (64 m, waypoints every 16 m).
constexpr int kCampusBuildings = 3;
constexpr double kCampusSpacing = 100;

WaypointGraph CampusGraph() {
  constexpr double kPathJitter = 1.0;
  WaypointGraph g;
  int previous_exit = -1;
  for (int k = 0; k < kCampusBuildings; ++k) {
    const double ox = kCampusSpacing * k;
    const BuildingNodes b = AddBuilding(&g, ox, 0);
    if (k == 0) {
      g.start = b.bottom0;
      g.first_target = b.bottom1;
    } else {
      int from = previous_exit;
      for (double x = ox - kCampusSpacing + 52; x < ox; x += 16) {
        const int node = AddNode(&g, x, 6, kPathJitter);
        Connect(&g, from, node);
        from = node;
      }
      Connect(&g, from, b.left1);
    }
    previous_exit = b.right1;
  }
  return g;
}

// Paths between junctions on a 5 x 5 grid of 25 m, interior junctions moved up to 4 m, four grid
// paths missing and three diagonals added. Junctions lie in [-50, 50] x [-50, 50]; the walk starts
// at the centre one.
WaypointGraph OpenGraph() {
  constexpr int kSide = 5;
  constexpr double kSpacing = 25;
  constexpr double kJitter = 1.0;
  WaypointGraph g;
  const auto id = [](int i, int j) { return j * kSide + i; };
  for (int j = 0; j < kSide; ++j) {
    for (int i = 0; i < kSide; ++i) {
      const bool inner_i = i > 0 && i < kSide - 1;
      const bool inner_j = j > 0 && j < kSide - 1;
      // The centre junction stays at the origin, where the walk starts.
      const bool centre = i == kSide / 2 && j == kSide / 2;
      const double dx = inner_i && !centre ? 4 * std::sin(1.7 * i + 2.9 * j) : 0;
      const double dy = inner_j && !centre ? 4 * std::cos(2.3 * i + 1.1 * j) : 0;
      AddNode(&g, kSpacing * (i - kSide / 2) + dx, kSpacing * (j - kSide / 2) + dy, kJitter);
    }
  }
  const auto missing = [&](int a, int b) {
    static constexpr int kMissing[][2] = {{6, 7}, {13, 14}, {17, 22}, {15, 20}};
    for (const auto& m : kMissing) {
      if ((m[0] == a && m[1] == b) || (m[0] == b && m[1] == a)) return true;
    }
    return false;
  };
  for (int j = 0; j < kSide; ++j) {
    for (int i = 0; i < kSide; ++i) {
      if (i + 1 < kSide && !missing(id(i, j), id(i + 1, j))) Connect(&g, id(i, j), id(i + 1, j));
      if (j + 1 < kSide && !missing(id(i, j), id(i, j + 1))) Connect(&g, id(i, j), id(i, j + 1));
    }
  }
  Connect(&g, id(1, 1), id(2, 2));
  Connect(&g, id(3, 3), id(4, 4));
  Connect(&g, id(2, 0), id(3, 1));
  g.start = id(2, 2);
  g.first_target = id(3, 2);
  g.explore = true;
  return g;
}

Status CheckRange(const char* name, double value, double low, bool low_open, double high,
                  bool high_open) {
  const bool above = low_open ? value > low : value >= low;
  const bool below = high_open ? value < high : value <= high;
  if (above && below) return Status::Ok();  // false for NaN
  return InvalidArgumentError(fmt::format("{} = {}: must be in {}{}, {}{}", name, value,
                                          low_open ? '(' : '[', low, high, high_open ? ')' : ']'));
}

Status CheckRange(const char* name, double value, const Interval& in) {
  return CheckRange(name, value, in.min, in.min_open, in.max, in.max_open);
}

Status Validate(const SimulatorOptions& o) {
  if (o.scenario != Scenario::kBuilding && o.scenario != Scenario::kOpen &&
      o.scenario != Scenario::kCampus) {
    return InvalidArgumentError(fmt::format("scenario = {}: must be kBuilding, kOpen or kCampus",
                                            static_cast<int>(o.scenario)));
  }
  GROVE_RETURN_IF_ERROR(CheckRange("minutes", o.minutes, WalkMinutesRange()));
  GROVE_RETURN_IF_ERROR(CheckRange("step_length_m", o.step_length_m, 0.1, false, 2, false));
  GROVE_RETURN_IF_ERROR(CheckRange("step_period_s", o.step_period_s, 0.1, false, 5, false));
  GROVE_RETURN_IF_ERROR(
      CheckRange("straight_probability", o.straight_probability, 0, false, 1, false));
  GROVE_RETURN_IF_ERROR(CheckRange("heading_drift_rad_per_sqrt_step",
                                   o.heading_drift_rad_per_sqrt_step, HeadingDriftRange()));
  GROVE_RETURN_IF_ERROR(CheckRange("scale_error", o.scale_error, ScaleErrorRange()));
  GROVE_RETURN_IF_ERROR(
      CheckRange("step_length_noise_m", o.step_length_noise_m, 0, false, 0.5, false));
  GROVE_RETURN_IF_ERROR(CheckRange("heading_noise_rad", o.heading_noise_rad, 0, false, 1, false));
  GROVE_RETURN_IF_ERROR(
      CheckRange("initial_heading_rad", o.initial_heading_rad, -kPi, false, kPi, false));
  return Status::Ok();
}

}  // namespace

Interval WalkMinutesRange() { return Interval::LeftOpen(0, 1440); }
Interval HeadingDriftRange() { return Interval::Closed(0, 0.5); }
Interval ScaleErrorRange() { return Interval::Open(-0.5, 0.5); }

Area ScenarioArea(Scenario scenario) {
  // The waypoints' extent plus the largest aim jitter and the sway of a step.
  if (scenario == Scenario::kOpen) return Area{-53, -53, 53, 53};
  if (scenario == Scenario::kCampus) {
    return Area{-1, -5, kCampusSpacing * (kCampusBuildings - 1) + 37, 22};
  }
  return Area{-1, -5, 37, 22};
}

StatusOr<SimulatedWalk> SimulateWalk(const SimulatorOptions& options) {
  GROVE_RETURN_IF_ERROR(Validate(options));
  const WaypointGraph graph = options.scenario == Scenario::kOpen     ? OpenGraph()
                              : options.scenario == Scenario::kCampus ? CampusGraph()
                                                                      : BuildingGraph();
  // Separate streams: the true walk must not change when only the odometry errors do.
  SimRandom walk_random(MixSeed(options.seed));
  SimRandom error_random(MixSeed(options.seed ^ 0x6F646F6D65747279ull));

  const double length_m = options.step_length_m;
  const int64_t step_count =
      static_cast<int64_t>(std::floor(options.minutes * 60.0 / options.step_period_s + 1e-9));
  SimulatedWalk walk;
  walk.truth.reserve(step_count + 1);
  walk.steps.reserve(step_count);
  walk.truth.push_back({0, 0, 0});

  std::vector<char> walked(graph.nodes.size() * graph.nodes.size(), 0);
  int previous = -1;
  int current = graph.start;
  int target = graph.first_target;
  double aim_x = 0;
  double aim_y = 0;
  const auto aim_at = [&](int node) {
    // Uniform in a disc: radius from sqrt(u).
    const double r = graph.nodes[node].jitter_m * std::sqrt(walk_random.Uniform());
    const double a = 2 * kPi * walk_random.Uniform();
    aim_x = graph.nodes[node].x_m + r * std::cos(a);
    aim_y = graph.nodes[node].y_m + r * std::sin(a);
  };
  const auto mark_walked = [&](int a, int b) {
    walked[a * graph.nodes.size() + b] = walked[b * graph.nodes.size() + a] = 1;
  };
  const auto choose_next = [&]() {
    const std::vector<int>& next = graph.nodes[current].next;
    std::vector<int> candidates;
    for (int n : next) {
      if (n != previous) candidates.push_back(n);
    }
    if (candidates.empty()) candidates = next;  // a dead end: turn back
    // A visit to a room is short: from inside, head back to the door more often than not.
    const int door = graph.nodes[current].door;
    if (door >= 0 && door != previous && walk_random.Uniform() < 0.6) return door;
    // People walk on rather than turn: most of the time take the way closest to straight
    // ahead, so corridors are walked as loops in a consistent direction.
    if (previous >= 0 && walk_random.Uniform() < options.straight_probability) {
      const Waypoint& from = graph.nodes[previous];
      const Waypoint& at = graph.nodes[current];
      const double heading = std::atan2(at.y_m - from.y_m, at.x_m - from.x_m);
      int best = candidates[0];
      double best_cos = -2;
      for (int n : candidates) {
        const Waypoint& to = graph.nodes[n];
        const double c = std::cos(std::atan2(to.y_m - at.y_m, to.x_m - at.x_m) - heading);
        if (c > best_cos + 1e-9) {
          best_cos = c;
          best = n;
        }
      }
      return best;
    }
    if (graph.explore && walk_random.Uniform() < 0.75) {
      std::vector<int> fresh;
      for (int n : candidates) {
        if (!walked[current * graph.nodes.size() + n]) fresh.push_back(n);
      }
      if (!fresh.empty()) candidates = std::move(fresh);
    }
    return candidates[walk_random.Index(candidates.size())];
  };
  aim_at(target);
  mark_walked(current, target);

  double x = 0;
  double y = 0;
  double sway_rad = 0;
  double heading_error_rad = options.initial_heading_rad;
  for (int64_t k = 1; k <= step_count; ++k) {
    double distance = std::hypot(aim_x - x, aim_y - y);
    // Near a waypoint, aim at the next one. Bounded in case waypoints are closer than a step.
    for (int guard = 0; guard < 16 && distance < 0.5 * length_m; ++guard) {
      previous = current;
      current = target;
      target = choose_next();
      mark_walked(current, target);
      aim_at(target);
      distance = std::hypot(aim_x - x, aim_y - y);
    }
    const double direction = std::atan2(aim_y - y, aim_x - x) + sway_rad;
    sway_rad = 0.7 * sway_rad + 0.03 * walk_random.Normal();
    const double wanted =
        std::clamp(length_m * (1 + 0.05 * walk_random.Normal()), 0.5 * length_m, 1.5 * length_m);
    const double length = std::min(wanted, distance);
    const double true_dx = length * std::cos(direction);
    const double true_dy = length * std::sin(direction);
    x += true_dx;
    y += true_dy;
    const double t = static_cast<double>(k) * options.step_period_s;
    walk.truth.push_back({t, x, y});

    // Odometry: scale and length noise along the step, then the heading error as a rotation.
    // With every error zero this is the true step exactly (factor 1, rotation by 0).
    heading_error_rad += options.heading_drift_rad_per_sqrt_step * error_random.Normal();
    const double length_noise = options.step_length_noise_m * error_random.Normal();
    const double rotation = heading_error_rad + options.heading_noise_rad * error_random.Normal();
    double vx;
    double vy;
    if (length > 0) {
      const double factor = std::max(0.0, (1 + options.scale_error) + length_noise / length);
      vx = factor * true_dx;
      vy = factor * true_dy;
    } else {
      vx = std::max(0.0, length_noise);
      vy = 0;
    }
    const double c = std::cos(rotation);
    const double s = std::sin(rotation);
    walk.steps.push_back({t, c * vx - s * vy, s * vx + c * vy, 0});
  }
  return walk;
}

std::string StepsCsv(const SimulatedWalk& walk) {
  std::string out = "t,dx,dy\n";
  auto it = std::back_inserter(out);
  for (const StepRecord& s : walk.steps) fmt::format_to(it, "{},{},{}\n", s.t_s, s.dx_m, s.dy_m);
  return out;
}

std::string TruthCsv(const SimulatedWalk& walk) {
  std::string out = "t,x,y\n";
  auto it = std::back_inserter(out);
  for (const TruthPoint& p : walk.truth) fmt::format_to(it, "{},{},{}\n", p.t_s, p.x_m, p.y_m);
  return out;
}

StatusOr<std::vector<StepRecord>> PaperWalk(double minutes) {
  SimulatorOptions sim;
  sim.scenario = Scenario::kOpen;
  sim.minutes = minutes;
  sim.seed = 1;
  StatusOr<SimulatedWalk> walk = SimulateWalk(sim);
  if (!walk.ok()) return walk.status();
  return std::move(walk->steps);
}

}  // namespace grove::tools
