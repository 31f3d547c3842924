#include "tools/sim/foot_imu_simulator.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>

#include "tools/sim/sim_random.h"

namespace grove::tools {
namespace {

constexpr double kPi = 3.14159265358979323846;

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<Vec3, 3>;

double Wrap(double a) {
  a = std::remainder(a, 2 * kPi);
  return a <= -kPi ? a + 2 * kPi : a;
}

// The swing's time profile, the minimum-jerk one (Flash and Hogan 1985): 0 to 1 with zero
// velocity and acceleration at both ends.
double Ease(double s) { return s * s * s * (10 + s * (-15 + 6 * s)); }
double EaseD1(double s) { return 30 * s * s * (1 - s) * (1 - s); }
double EaseD2(double s) { return 60 * s * (1 - s) * (1 - 2 * s); }

// The pitch lobes over the swing, c s^3 (1 - s)^5 (toe off, peak 1 at s = 3/8) and its mirror
// (heel strike, peak at 5/8): the foot turns toes down, then quickly through level to toes up,
// the rate rising from the stance as s^2 (the angular acceleration continuous).
constexpr double kLobeScale = 1.0 / (27.0 / 512 * 3125.0 / 32768);  // 1 / max of s^3 (1 - s)^5
double Lobe(double s) {
  if (s <= 0 || s >= 1) return 0;
  const double v = 1 - s;
  return kLobeScale * s * s * s * v * v * v * v * v;
}
double LobeD1(double s) {
  if (s <= 0 || s >= 1) return 0;
  const double v = 1 - s;
  return kLobeScale * s * s * v * v * v * v * (3 * v - 5 * s);
}

// The height bump on [0, 1]: 64 (s (1 - s))^3, 0 at the ends with two derivatives, 1 at the
// middle.
double BumpD2(double s) {
  if (s <= 0 || s >= 1) return 0;
  const double w = s * (1 - s);
  return 384 * w * ((1 - 2 * s) * (1 - 2 * s) - w);
}

// The foot's pose and its derivatives at one instant, in the truth frame.
struct FootMotion {
  Vec3 accel = {0, 0, 0};  // second derivative of position
  double pitch = 0;        // positive: toes down
  double pitch_rate = 0;
  double heading = 0;
  double heading_rate = 0;
};

// The motion in the swing from stance a to stance b at time t.
FootMotion SwingMotion(const TrueStance& a, const TrueStance& b, const GaitModel& gait, double t) {
  const double d = b.begin_s - a.end_s;
  const double s = (t - a.end_s) / d;
  FootMotion m;
  const double dx = b.x_m - a.x_m;
  const double dy = b.y_m - a.y_m;
  const double e2 = EaseD2(s) / (d * d);
  m.accel = {dx * e2, dy * e2, gait.clearance_m * BumpD2(s) / (d * d)};
  m.pitch = gait.toe_off_pitch_rad * Lobe(s) - gait.heel_strike_pitch_rad * Lobe(1 - s);
  m.pitch_rate =
      (gait.toe_off_pitch_rad * LobeD1(s) + gait.heel_strike_pitch_rad * LobeD1(1 - s)) / d;
  m.heading = a.heading_rad + (b.heading_rad - a.heading_rad) * Ease(s);
  m.heading_rate = (b.heading_rad - a.heading_rad) * EaseD1(s) / d;
  return m;
}

Status CheckRange(const char* name, double value, double low, double high) {
  if (value >= low && value <= high) return Status::Ok();  // false for NaN
  return InvalidArgumentError(fmt::format("{} = {}: must be in [{}, {}]", name, value, low, high));
}

Status Validate(const FootImuSimOptions& o) {
  GROVE_RETURN_IF_ERROR(CheckRange("rate_hz", o.rate_hz, 50, 2000));
  GROVE_RETURN_IF_ERROR(CheckRange("stance_fraction", o.gait.stance_fraction, 0.1, 0.8));
  GROVE_RETURN_IF_ERROR(CheckRange("rest_s", o.gait.rest_s, 0.5, 60));
  GROVE_RETURN_IF_ERROR(CheckRange("clearance_m", o.gait.clearance_m, 0, 0.5));
  GROVE_RETURN_IF_ERROR(CheckRange("toe_off_pitch_rad", o.gait.toe_off_pitch_rad, 0, 1.5));
  GROVE_RETURN_IF_ERROR(CheckRange("heel_strike_pitch_rad", o.gait.heel_strike_pitch_rad, 0, 1.5));
  GROVE_RETURN_IF_ERROR(CheckRange("gravity_mps2", o.gravity_mps2, 9.7, 9.9));
  GROVE_RETURN_IF_ERROR(CheckRange("bits", o.mems.bits, 0, 32));
  for (auto [name, v] :
       {std::pair{"accel_noise_mps2_per_sqrt_hz", o.mems.accel_noise_mps2_per_sqrt_hz},
        std::pair{"gyro_noise_radps_per_sqrt_hz", o.mems.gyro_noise_radps_per_sqrt_hz},
        std::pair{"accel_bias_mps2", o.mems.accel_bias_mps2},
        std::pair{"gyro_bias_radps", o.mems.gyro_bias_radps},
        std::pair{"accel_bias_walk_mps3_per_sqrt_hz", o.mems.accel_bias_walk_mps3_per_sqrt_hz},
        std::pair{"gyro_bias_walk_radps2_per_sqrt_hz", o.mems.gyro_bias_walk_radps2_per_sqrt_hz},
        std::pair{"accel_scale_sigma", o.mems.accel_scale_sigma},
        std::pair{"gyro_scale_sigma", o.mems.gyro_scale_sigma},
        std::pair{"accel_misalignment_rad", o.mems.accel_misalignment_rad},
        std::pair{"gyro_misalignment_rad", o.mems.gyro_misalignment_rad}}) {
    GROVE_RETURN_IF_ERROR(CheckRange(name, v, 0, 1));
  }
  if (!(o.mems.accel_range_mps2 > 0) || !(o.mems.gyro_range_radps > 0)) {
    return InvalidArgumentError(fmt::format("ranges = {}, {}: must be > 0", o.mems.accel_range_mps2,
                                            o.mems.gyro_range_radps));
  }
  return Status::Ok();
}

// One triad of a sensor (accelerometer or gyroscope) with its errors for one recording.
class Triad {
 public:
  Triad(SimRandom* random, double bias, double scale, double misalignment, double noise_density,
        double bias_walk, double range, int bits, double rate_hz)
      : noise_(noise_density * std::sqrt(rate_hz)),
        walk_(bias_walk / std::sqrt(rate_hz)),
        range_(range),
        lsb_(bits > 0 ? range / std::ldexp(1.0, bits - 1) : 0) {
    for (int i = 0; i < 3; ++i) bias_[i] = bias * random->Normal();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        matrix_[i][j] = (i == j ? 1 + scale * random->Normal() : misalignment * random->Normal());
      }
    }
  }

  Vec3 Measure(const Vec3& truth, SimRandom* random) {
    Vec3 out;
    for (int i = 0; i < 3; ++i) bias_[i] += walk_ * random->Normal();
    for (int i = 0; i < 3; ++i) {
      double v = bias_[i] + noise_ * random->Normal();
      for (int j = 0; j < 3; ++j) v += matrix_[i][j] * truth[j];
      if (lsb_ > 0) v = std::round(v / lsb_) * lsb_;
      out[i] = std::clamp(v, -range_, range_ - lsb_);
    }
    return out;
  }

 private:
  double noise_;  // per sample
  double walk_;   // bias increment per sample
  double range_;
  double lsb_;
  Vec3 bias_;
  Mat3 matrix_;
};

// The stances: one on every second truth point, each facing along the path there.
std::vector<TrueStance> Stances(const SimulatedWalk& walk, const FootImuSimOptions& o,
                                double* stance_s) {
  const auto& truth = walk.truth;
  std::vector<size_t> index;
  for (size_t k = 0; k < truth.size(); k += 2) index.push_back(k);
  const double period =
      index.size() > 1 ? (truth[index.back()].t_s - truth[0].t_s) / (index.size() - 1) : 1.0;
  *stance_s = o.gait.stance_fraction * period;
  std::vector<TrueStance> stances;
  double heading = 0;
  for (size_t j = 0; j < index.size(); ++j) {
    const TruthPoint& p = truth[index[j]];
    const TruthPoint& before = truth[index[j > 0 ? j - 1 : j]];
    const TruthPoint& after = truth[index[j + 1 < index.size() ? j + 1 : j]];
    const double dx = after.x_m - before.x_m;
    const double dy = after.y_m - before.y_m;
    const double direction = dx == 0 && dy == 0 ? heading : std::atan2(dy, dx);
    heading = j == 0 ? direction : heading + Wrap(direction - heading);
    TrueStance s;
    s.begin_s = p.t_s - *stance_s / 2;
    s.end_s = p.t_s + *stance_s / 2;
    s.x_m = p.x_m;
    s.y_m = p.y_m;
    s.heading_rad = heading;
    s.truth_index = static_cast<int64_t>(index[j]);
    stances.push_back(s);
  }
  stances.front().begin_s = truth.front().t_s - o.gait.rest_s;
  stances.back().end_s = truth[index.back()].t_s + o.gait.rest_s;
  return stances;
}

}  // namespace

MemsModel MemsModel::None() {
  MemsModel m;
  m.accel_noise_mps2_per_sqrt_hz = m.gyro_noise_radps_per_sqrt_hz = 0;
  m.accel_bias_mps2 = m.gyro_bias_radps = 0;
  m.accel_bias_walk_mps3_per_sqrt_hz = m.gyro_bias_walk_radps2_per_sqrt_hz = 0;
  m.accel_scale_sigma = m.gyro_scale_sigma = 0;
  m.accel_misalignment_rad = m.gyro_misalignment_rad = 0;
  m.accel_range_mps2 = m.gyro_range_radps = std::numeric_limits<double>::max();
  m.bits = 0;
  return m;
}

StatusOr<SimulatedFootImu> SimulateFootImu(const SimulatedWalk& walk, const FootImuSimOptions& o) {
  GROVE_RETURN_IF_ERROR(Validate(o));
  if (walk.truth.empty()) return InvalidArgumentError("the walk has no truth points");
  SimulatedFootImu out;
  double stance_s = 0;
  out.stances = Stances(walk, o, &stance_s);
  for (size_t j = 0; j + 1 < out.stances.size(); ++j) {
    const double swing = out.stances[j + 1].begin_s - out.stances[j].end_s;
    if (!(swing >= 0.2)) {
      return InvalidArgumentError(fmt::format(
          "stance_fraction = {}: the swing after stance {} would last {:.3f} s, under 0.2 s "
          "(stride period {:.3f} s)",
          o.gait.stance_fraction, j, swing, out.stances[j + 1].begin_s - out.stances[j].begin_s));
    }
  }
  SimRandom random(MixSeed(o.seed ^ 0x666F6F74696D75ull));
  const MemsModel& m = o.mems;
  Triad accel(&random, m.accel_bias_mps2, m.accel_scale_sigma, m.accel_misalignment_rad,
              m.accel_noise_mps2_per_sqrt_hz, m.accel_bias_walk_mps3_per_sqrt_hz,
              m.accel_range_mps2, m.bits, o.rate_hz);
  Triad gyro(&random, m.gyro_bias_radps, m.gyro_scale_sigma, m.gyro_misalignment_rad,
             m.gyro_noise_radps_per_sqrt_hz, m.gyro_bias_walk_radps2_per_sqrt_hz,
             m.gyro_range_radps, m.bits, o.rate_hz);

  const double t0 = out.stances.front().begin_s;
  const double t1 = out.stances.back().end_s;
  const int64_t n = static_cast<int64_t>(std::floor((t1 - t0) * o.rate_hz)) + 1;
  out.samples.reserve(static_cast<size_t>(n));
  size_t j = 0;  // the stance at or before t
  for (int64_t k = 0; k < n; ++k) {
    const double t = t0 + static_cast<double>(k) / o.rate_hz;
    while (j + 1 < out.stances.size() && t >= out.stances[j + 1].begin_s) ++j;
    FootMotion motion;
    if (t <= out.stances[j].end_s || j + 1 == out.stances.size()) {
      motion.heading = out.stances[j].heading_rad;
    } else {
      motion = SwingMotion(out.stances[j], out.stances[j + 1], o.gait, t);
    }
    // C = Rz(heading) Ry(pitch): the sensor frame in the truth frame.
    const double cp = std::cos(motion.pitch), sp = std::sin(motion.pitch);
    const double ch = std::cos(motion.heading), sh = std::sin(motion.heading);
    const Vec3 a = {motion.accel[0], motion.accel[1], motion.accel[2] + o.gravity_mps2};
    // f = C^T a, with C^T = Ry(pitch)^T Rz(heading)^T.
    const double ax = ch * a[0] + sh * a[1];
    const double ay = -sh * a[0] + ch * a[1];
    const Vec3 f = {cp * ax - sp * a[2], ay, sp * ax + cp * a[2]};
    const Vec3 w = {-sp * motion.heading_rate, motion.pitch_rate, cp * motion.heading_rate};
    const Vec3 fm = accel.Measure(f, &random);
    const Vec3 wm = gyro.Measure(w, &random);
    out.samples.push_back(ImuSample{t, {fm[0], fm[1], fm[2]}, {wm[0], wm[1], wm[2]}});
  }
  return out;
}

std::string ImuCsv(const SimulatedFootImu& imu, int digits) {
  std::string out = "t,ax,ay,az,gx,gy,gz\n";
  auto it = std::back_inserter(out);
  for (const ImuSample& s : imu.samples) {
    if (digits <= 0) {
      fmt::format_to(it, "{},{},{},{},{},{},{}\n", s.t_s, s.accel_mps2[0], s.accel_mps2[1],
                     s.accel_mps2[2], s.gyro_radps[0], s.gyro_radps[1], s.gyro_radps[2]);
    } else {
      // Time to the microsecond, in its shortest form.
      fmt::format_to(it, "{},{:.{}g},{:.{}g},{:.{}g},{:.{}g},{:.{}g},{:.{}g}\n",
                     std::round(s.t_s * 1e6) / 1e6, s.accel_mps2[0], digits, s.accel_mps2[1],
                     digits, s.accel_mps2[2], digits, s.gyro_radps[0], digits, s.gyro_radps[1],
                     digits, s.gyro_radps[2], digits);
    }
  }
  return out;
}

std::string StancesCsv(const SimulatedFootImu& imu) {
  std::string out = "begin,end,x,y,heading\n";
  auto it = std::back_inserter(out);
  for (const TrueStance& s : imu.stances) {
    fmt::format_to(it, "{},{},{},{},{}\n", s.begin_s, s.end_s, s.x_m, s.y_m, s.heading_rad);
  }
  return out;
}

}  // namespace grove::tools
