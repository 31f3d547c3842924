// The bounds of every value the engines' step calls take, in one table. The facades check them
// before changing anything (FastSlam::Control and Scan, FootSlam::Step and SetStartTime) and
// refuse a value outside them with InvalidArgument, the engine unchanged; the CLI's readers check
// each field of a file with the same functions and add FILE:LINE:COLUMN. So C++, C, Python and
// the CLI refuse the same values in the same words, "NAME = VALUE: must be RULE":
//
//   grove::Status s = grove::CheckInput(grove::InputField::kSpeed, 1e30);
//   if (s.ok()) return grove::InternalError("1e30 m/s was accepted");
//   // s.message(): "speed = 1e+30: must be within +-1000 m/s"
//
// Within these bounds no single step of a finite state makes a non-finite one: a control moves
// the vehicle at most kMaxAbsSpeedMps x 2 kMaxAbsTimeS, a detection puts its landmark at most
// kMaxRangeM from the vehicle with a covariance that grows as range^2, and a FootSLAM step moves
// a particle at most kMaxAbsStepM along each axis. A step that fails inside the model all the
// same (a degenerated filter, a particle leaving a fixed grid, out of memory) stops the engine,
// and its message says so.
#ifndef GROVE_INPUT_RULES_H_
#define GROVE_INPUT_RULES_H_

#include <cstdint>
#include <span>

#include "grove/export.h"
#include "grove/status.h"

namespace grove {

struct FastSlamConfig;

// |t| of every time, seconds: a second is still resolved at 1e12 s (about 31,700 years).
inline constexpr double kMaxAbsTimeS = 1e12;
// |speed| of a FastSLAM control, m/s (beyond any ground vehicle).
inline constexpr double kMaxAbsSpeedMps = 1e3;
// Largest range of a FastSLAM detection, metres (FastSlamConfig::sensor_range_m's bound).
inline constexpr double kMaxRangeM = 1e6;
// |dx| and |dy| of a FootSLAM step, metres.
inline constexpr double kMaxAbsStepM = 1e6;
// Landmark ids are in [0, kLandmarkIdLimit) (2^31).
inline constexpr int64_t kLandmarkIdLimit = int64_t{1} << 31;

// A value of an input record.
enum class InputField {
  kTime,      // t (s) of a control, scan or step
  kSpeed,     // a FastSLAM control's speed (m/s)
  kSteering,  // a FastSLAM control's steering angle (rad)
  kRange,     // a detection's range (m)
  kBearing,   // a detection's bearing (rad, counter-clockwise from the heading)
  kStepDx,    // a FootSLAM step's dx (m, odometry frame)
  kStepDy,    // a FootSLAM step's dy (m)
};

// One row of the table: the value's name in messages, its interval and the rule as words.
struct InputRule {
  InputField field;
  const char* name;  // "speed"
  double min;
  double max;
  bool min_open;     // min itself is refused
  bool max_open;     // max itself is refused
  const char* rule;  // "within +-1000 m/s"
};

// Every rule, in InputField order.
GROVE_EXPORT std::span<const InputRule> InputRules();

// Ok when `value` keeps `field`'s rule; otherwise InvalidArgument "NAME = VALUE: must be finite"
// for NaN and infinities, "NAME = VALUE: must be RULE" for a value outside the interval.
GROVE_EXPORT Status CheckInput(InputField field, double value);

// A FastSLAM control's steering angle under `config`: CheckInput(kSteering), and for the
// Guivant-Nebot vehicle also 1 - tan(steering) H / L > 0 (the wheel speed's conversion).
GROVE_EXPORT Status CheckSteering(const FastSlamConfig& config, double steer_rad);

// A detection's landmark id: in [0, 2^31) under known association; under unknown association
// also -1 (none).
GROVE_EXPORT Status CheckLandmarkId(int64_t id, bool known_association);

}  // namespace grove

#endif  // GROVE_INPUT_RULES_H_
