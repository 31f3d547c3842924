#include "grove/input_rules.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <numbers>

#include "engine/fastslam/vehicle_model.h"
#include "grove/fastslam.h"

namespace grove {
namespace {

constexpr double kPi = std::numbers::pi;

constexpr std::array<InputRule, 7> kRules = {{
    {InputField::kTime, "t", -kMaxAbsTimeS, kMaxAbsTimeS, false, false, "within +-1e12 s"},
    {InputField::kSpeed, "speed", -kMaxAbsSpeedMps, kMaxAbsSpeedMps, false, false,
     "within +-1000 m/s"},
    {InputField::kSteering, "steering", -kPi / 2, kPi / 2, true, true, "in (-pi/2, pi/2) rad"},
    {InputField::kRange, "range", 0, kMaxRangeM, false, false, "in [0, 1e6] m"},
    {InputField::kBearing, "bearing", -kPi, kPi, true, false, "in (-pi, pi] rad"},
    {InputField::kStepDx, "dx", -kMaxAbsStepM, kMaxAbsStepM, false, false, "within +-1e6 m"},
    {InputField::kStepDy, "dy", -kMaxAbsStepM, kMaxAbsStepM, false, false, "within +-1e6 m"},
}};

constexpr bool RulesInFieldOrder() {
  for (size_t k = 0; k < kRules.size(); ++k) {
    if (static_cast<size_t>(kRules[k].field) != k) return false;
  }
  return true;
}
static_assert(RulesInFieldOrder(), "kRules[k] is the rule of InputField k");

}  // namespace

std::span<const InputRule> InputRules() { return kRules; }

Status CheckInput(InputField field, double value) {
  const InputRule& r = kRules[static_cast<size_t>(field)];
  if (!std::isfinite(value)) {
    return InvalidArgumentError(fmt::format("{} = {}: must be finite", r.name, value));
  }
  const bool above = r.min_open ? value > r.min : value >= r.min;
  const bool below = r.max_open ? value < r.max : value <= r.max;
  if (!above || !below) {
    return InvalidArgumentError(fmt::format("{} = {}: must be {}", r.name, value, r.rule));
  }
  return Status::Ok();
}

Status CheckSteering(const FastSlamConfig& config, double steer_rad) {
  GROVE_RETURN_IF_ERROR(CheckInput(InputField::kSteering, steer_rad));
  if (!fastslam::SteeringUsable(fastslam::VehicleGeometry::Of(config), steer_rad)) {
    return InvalidArgumentError(fmt::format(
        "steering = {}: must keep 1 - tan(steering) H / L > 0 for the {} vehicle (H = {} m, "
        "L = {} m)",
        steer_rad, FastSlamVehicleName(config.vehicle), config.encoder_offset_m,
        config.wheelbase_m));
  }
  return Status::Ok();
}

Status CheckLandmarkId(int64_t id, bool known_association) {
  if (id >= 0 && id < kLandmarkIdLimit) return Status::Ok();
  if (!known_association && id == -1) return Status::Ok();
  return InvalidArgumentError(
      known_association
          ? fmt::format("id = {}: must be an integer in [0, 2^31) under known association", id)
          : fmt::format("id = {}: must be -1 (none) or an integer in [0, 2^31) under unknown "
                        "association",
                        id));
}

}  // namespace grove
