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

VehiclePose MoveVehicle(const VehicleGeometry& g, const VehiclePose& p, double v_mps,
                        double steer_rad, double dt_s) {
  VehiclePose out;
  if (g.kind == FastSlamVehicle::kBailey) {
    const double a = steer_rad + p.heading_rad;
    out.x_m = p.x_m + v_mps * dt_s * std::cos(a);
    out.y_m = p.y_m + v_mps * dt_s * std::sin(a);
    out.heading_rad = WrapAngle(p.heading_rad + v_mps * dt_s * std::sin(steer_rad) / g.wheelbase_m);
    return out;
  }
  const double t = std::tan(steer_rad);
  const double vc = v_mps / (1 - t * g.encoder_offset_m / g.wheelbase_m);
  const double c = std::cos(p.heading_rad), s = std::sin(p.heading_rad);
  const double turn = vc / g.wheelbase_m * t;
  out.x_m = p.x_m + dt_s * (vc * c - turn * (g.laser_forward_m * s + g.laser_left_m * c));
  out.y_m = p.y_m + dt_s * (vc * s + turn * (g.laser_forward_m * c - g.laser_left_m * s));
  out.heading_rad = WrapAngle(p.heading_rad + dt_s * turn);
  return out;
}

void VehicleJacobians(const VehicleGeometry& g, const VehiclePose& p, double v_mps,
                      double steer_rad, double dt_s, Eigen::Matrix3d* d_pose,
                      Eigen::Matrix<double, 3, 2>* d_control) {
  d_pose->setIdentity();
  if (g.kind == FastSlamVehicle::kBailey) {
    const double a = steer_rad + p.heading_rad;
    const double ca = std::cos(a), sa = std::sin(a);
    (*d_pose)(0, 2) = -v_mps * dt_s * sa;
    (*d_pose)(1, 2) = v_mps * dt_s * ca;
    *d_control << dt_s * ca, -v_mps * dt_s * sa,  //
        dt_s * sa, v_mps * dt_s * ca,             //
        dt_s * std::sin(steer_rad) / g.wheelbase_m,
        v_mps * dt_s * std::cos(steer_rad) / g.wheelbase_m;
    return;
  }
  const double L = g.wheelbase_m, H = g.encoder_offset_m;
  const double a = g.laser_forward_m, b = g.laser_left_m;
  const double t = std::tan(steer_rad);
  const double sec2 = 1 + t * t;
  const double k = 1 - t * H / L;
  const double vc = v_mps / k;
  const double dvc_dv = 1 / k;
  const double dvc_dg = v_mps * (H / L) * sec2 / (k * k);
  const double c = std::cos(p.heading_rad), s = std::sin(p.heading_rad);
  // dx = dt vc A, dy = dt vc B, dphi = dt vc t / L.
  const double A = c - t / L * (a * s + b * c);
  const double B = s + t / L * (a * c - b * s);
  const double dA_dg = -sec2 / L * (a * s + b * c);
  const double dB_dg = sec2 / L * (a * c - b * s);
  const double dA_dphi = -s - t / L * (a * c - b * s);  // = -B
  const double dB_dphi = c + t / L * (-a * s - b * c);  // = A
  (*d_pose)(0, 2) = dt_s * vc * dA_dphi;
  (*d_pose)(1, 2) = dt_s * vc * dB_dphi;
  *d_control << dt_s * dvc_dv * A, dt_s * (dvc_dg * A + vc * dA_dg),  //
      dt_s * dvc_dv * B, dt_s * (dvc_dg * B + vc * dB_dg),            //
      dt_s * dvc_dv * t / L, dt_s * (dvc_dg * t + vc * sec2) / L;
}

}  // namespace grove::fastslam
