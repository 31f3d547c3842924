// The vehicle models of landmark FastSLAM: one Euler step of a control interval, and its
// Jacobians for FastSLAM 2.0's pose covariance. Models and parameters: grove/fastslam.h.
//
// Bailey (his vehicle_model.m; sin(G) / B, not sin(G / B)):
//   x' = x + V dt cos(G + phi),  y' = y + V dt sin(G + phi),  phi' = phi + V dt sin(G) / B.
// Guivant-Nebot (the Victoria Park vehicle; Guivant and Nebot 2001, and engine/fastslam/README.md,
// "Victoria Park"): with the axle-centre
// speed v_c = V / (1 - tan(G) H / L),
//   x' = x + dt (v_c cos phi - (v_c / L) tan G (a sin phi + b cos phi)),
//   y' = y + dt (v_c sin phi + (v_c / L) tan G (a cos phi - b sin phi)),
//   phi' = phi + dt (v_c / L) tan G.
// The new heading is wrapped to (-pi, pi] in both.
//
// Thread safety: values only.
#ifndef GROVE_ENGINE_FASTSLAM_VEHICLE_MODEL_H_
#define GROVE_ENGINE_FASTSLAM_VEHICLE_MODEL_H_

#include <Eigen/Core>

#include "engine/fastslam/landmark_math.h"
#include "grove/fastslam.h"

namespace grove::fastslam {

struct VehicleGeometry {
  FastSlamVehicle kind = FastSlamVehicle::kBailey;
  double wheelbase_m = 4;
  double encoder_offset_m = 0;
  double laser_forward_m = 0;
  double laser_left_m = 0;

  static VehicleGeometry Of(const FastSlamConfig& c) {
    return {c.vehicle, c.wheelbase_m, c.encoder_offset_m, c.laser_forward_m, c.laser_left_m};
  }
};

// Whether the model can use steering angle `steer_rad`: any finite angle for Bailey's; for
// Guivant-Nebot's |steer| < pi/2 and 1 - tan(steer) H / L > 0 (the wheel speed's conversion).
bool SteeringUsable(const VehicleGeometry& g, double steer_rad);

// What a step costs that does not depend on the pose: computed once per control and shared by
// every particle that moves with it (FastSLAM 2.0 moves all of them with the same control).
struct ControlTerms {
  double v_mps = 0, steer_rad = 0, dt_s = 0;
  double sin_g = 0, cos_g = 0;
  double tan_g = 0, k = 1;  // Guivant-Nebot: tan G and 1 - tan(G) H / L
  double turn_rad = 0;      // the heading change of the step
};
// REQUIRES: SteeringUsable(g, steer_rad).
ControlTerms ControlTermsOf(const VehicleGeometry& g, double v_mps, double steer_rad, double dt_s);

// The cosine and sine a step computes from the pose, kept for the Jacobians.
struct StepTrig {
  double c = 1, s = 0;  // Bailey: of G + phi; Guivant-Nebot: of phi
};

// One Euler step with the control of `u` from p; *trig (may be null) gets what the Jacobians
// need.
VehiclePose MoveVehicle(const VehicleGeometry& g, const ControlTerms& u, const VehiclePose& p,
                        StepTrig* trig = nullptr);
// The same from the raw control. REQUIRES: SteeringUsable(g, steer_rad).
inline VehiclePose MoveVehicle(const VehicleGeometry& g, const VehiclePose& p, double v_mps,
                               double steer_rad, double dt_s) {
  return MoveVehicle(g, ControlTermsOf(g, v_mps, steer_rad, dt_s), p);
}

// The Jacobians of MoveVehicle with respect to the pose (x, y, phi) and the control (V, G), at
// the pose whose step gave `trig`.
void VehicleJacobians(const VehicleGeometry& g, const ControlTerms& u, const StepTrig& trig,
                      Eigen::Matrix3d* d_pose, Eigen::Matrix<double, 3, 2>* d_control);
// The same from the raw control and pose.
void VehicleJacobians(const VehicleGeometry& g, const VehiclePose& p, double v_mps,
                      double steer_rad, double dt_s, Eigen::Matrix3d* d_pose,
                      Eigen::Matrix<double, 3, 2>* d_control);

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_VEHICLE_MODEL_H_
