#include "engine/fastslam/vehicle_model.h"

#include <cmath>
#include <numbers>

namespace grove::fastslam {

bool SteeringUsable(const VehicleGeometry& g, double steer_rad) {
  if (!std::isfinite(steer_rad)) return false;
  if (g.kind == FastSlamVehicle::kBailey) return true;
  if (!(std::fabs(steer_rad) < std::numbers::pi / 2)) return false;
  return 1 - std::tan(steer_rad) * g.encoder_offset_m / g.wheelbase_m > 0;
}

ControlTerms ControlTermsOf(const VehicleGeometry& g, double v_mps, double steer_rad, double dt_s) {
  ControlTerms u;
  u.v_mps = v_mps;
  u.steer_rad = steer_rad;
  u.dt_s = dt_s;
  u.sin_g = std::sin(steer_rad);
  u.cos_g = std::cos(steer_rad);
  if (g.kind == FastSlamVehicle::kBailey) {
    u.turn_rad = v_mps * dt_s * u.sin_g / g.wheelbase_m;
  } else {
    u.tan_g = std::tan(steer_rad);
    u.k = 1 - u.tan_g * g.encoder_offset_m / g.wheelbase_m;
    const double vc = v_mps / u.k;
    u.turn_rad = dt_s * (vc / g.wheelbase_m * u.tan_g);
  }
  return u;
}

VehiclePose MoveVehicle(const VehicleGeometry& g, const ControlTerms& u, const VehiclePose& p,
                        StepTrig* trig) {
  VehiclePose out;
  StepTrig t;
  if (g.kind == FastSlamVehicle::kBailey) {
    const double a = u.steer_rad + p.heading_rad;
    t = {std::cos(a), std::sin(a)};
    out.x_m = p.x_m + u.v_mps * u.dt_s * t.c;
    out.y_m = p.y_m + u.v_mps * u.dt_s * t.s;
  } else {
    t = {std::cos(p.heading_rad), std::sin(p.heading_rad)};
    const double vc = u.v_mps / u.k;
    const double turn = vc / g.wheelbase_m * u.tan_g;
    out.x_m = p.x_m + u.dt_s * (vc * t.c - turn * (g.laser_forward_m * t.s + g.laser_left_m * t.c));
    out.y_m = p.y_m + u.dt_s * (vc * t.s + turn * (g.laser_forward_m * t.c - g.laser_left_m * t.s));
  }
  out.heading_rad = WrapAngle(p.heading_rad + u.turn_rad);
  if (trig != nullptr) *trig = t;
  return out;
}

void VehicleJacobians(const VehicleGeometry& g, const ControlTerms& u, const StepTrig& trig,
                      Eigen::Matrix3d* d_pose, Eigen::Matrix<double, 3, 2>* d_control) {
  d_pose->setIdentity();
  const double dt_s = u.dt_s, v_mps = u.v_mps;
  if (g.kind == FastSlamVehicle::kBailey) {
    const double ca = trig.c, sa = trig.s;
    (*d_pose)(0, 2) = -v_mps * dt_s * sa;
    (*d_pose)(1, 2) = v_mps * dt_s * ca;
    *d_control << dt_s * ca, -v_mps * dt_s * sa,  //
        dt_s * sa, v_mps * dt_s * ca,             //
        dt_s * u.sin_g / g.wheelbase_m, v_mps * dt_s * u.cos_g / g.wheelbase_m;
    return;
  }
  const double L = g.wheelbase_m, H = g.encoder_offset_m;
  const double a = g.laser_forward_m, b = g.laser_left_m;
  const double t = u.tan_g;
  const double sec2 = 1 + t * t;
  const double k = u.k;
  const double vc = v_mps / k;
  const double dvc_dv = 1 / k;
  const double dvc_dg = v_mps * (H / L) * sec2 / (k * k);
  const double c = trig.c, s = trig.s;
  // dx = dt vc A, dy = dt vc B, dphi = dt vc t / L.
  const double A = c - t / L * (a * s + b * c);
  const double B = s + t / L * (a * c - b * s);
  const double dA_dg = -sec2 / L * (a * s + b * c);
  const double dB_dg = sec2 / L * (a * c - b * s);
  (*d_pose)(0, 2) = -dt_s * vc * B;                                   // dA/dphi = -B
  (*d_pose)(1, 2) = dt_s * vc * A;                                    // dB/dphi = A
  *d_control << dt_s * dvc_dv * A, dt_s * (dvc_dg * A + vc * dA_dg),  //
      dt_s * dvc_dv * B, dt_s * (dvc_dg * B + vc * dB_dg),            //
      dt_s * dvc_dv * t / L, dt_s * (dvc_dg * t + vc * sec2) / L;
}

void VehicleJacobians(const VehicleGeometry& g, const VehiclePose& p, double v_mps,
                      double steer_rad, double dt_s, Eigen::Matrix3d* d_pose,
                      Eigen::Matrix<double, 3, 2>* d_control) {
  const ControlTerms u = ControlTermsOf(g, v_mps, steer_rad, dt_s);
  StepTrig trig;
  MoveVehicle(g, u, p, &trig);
  VehicleJacobians(g, u, trig, d_pose, d_control);
}

}  // namespace grove::fastslam
