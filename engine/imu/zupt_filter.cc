#include "engine/imu/zupt_filter.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace grove::imu {
namespace {

constexpr double kPi = 3.14159265358979323846;
// State offsets.
constexpr int kP = 0, kV = 3, kTheta = 6, kBa = 9, kBg = 12, kClone = 15;

Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

// The unit quaternion of the rotation vector `phi`.
Eigen::Quaterniond Exp(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) {
    return Eigen::Quaterniond(1, phi.x() / 2, phi.y() / 2, phi.z() / 2).normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, phi / angle));
}

double WrapAngle(double a) {
  a = std::remainder(a, 2 * kPi);
  return a <= -kPi ? a + 2 * kPi : a;
}

}  // namespace

double NormalGravity(double latitude_rad, double height_m) {
  // WGS-84: equatorial gravity, Somigliana's constant k and the first eccentricity squared.
  constexpr double kGammaE = 9.7803253359;
  constexpr double kK = 0.00193185265241;
  constexpr double kE2 = 0.00669437999013;
  const double s2 = std::sin(latitude_rad) * std::sin(latitude_rad);
  return kGammaE * (1 + kK * s2) / std::sqrt(1 - kE2 * s2) - 3.086e-6 * height_m;
}

Eigen::Matrix3d RotationFromEuler(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d EulerFromRotation(const Eigen::Matrix3d& c) {
  const double pitch = -std::asin(std::clamp(c(2, 0), -1.0, 1.0));
  return {std::atan2(c(2, 1), c(2, 2)), pitch, std::atan2(c(1, 0), c(0, 0))};
}

Eigen::Vector2d TiltFromSpecificForce(const Eigen::Vector3d& f) {
  return {std::atan2(f.y(), f.z()), std::atan2(-f.x(), std::hypot(f.y(), f.z()))};
}

void ZuptFilter::Start(const Eigen::Matrix3d& attitude, const Eigen::Vector3d& gyro_bias,
                       const InitialSigmas& s) {
  p_.setZero();
  v_.setZero();
  q_ = Eigen::Quaterniond(attitude).normalized();
  ba_.setZero();
  bg_ = gyro_bias;
  p_cov_.setZero();
  p_cov_.block<3, 3>(kV, kV).diagonal().setConstant(s.velocity * s.velocity);
  p_cov_(kTheta, kTheta) = p_cov_(kTheta + 1, kTheta + 1) = s.tilt * s.tilt;
  p_cov_(kTheta + 2, kTheta + 2) = s.heading * s.heading;
  p_cov_.block<3, 3>(kBa, kBa).diagonal().setConstant(s.accel_bias * s.accel_bias);
  p_cov_.block<3, 3>(kBg, kBg).diagonal().setConstant(s.gyro_bias * s.gyro_bias);
  Clone();
}

double ZuptFilter::heading() const {
  const Eigen::Matrix3d c = attitude();
  return std::atan2(c(1, 0), c(0, 0));
}

Eigen::RowVector3d ZuptFilter::HeadingJacobian() const {
  const Eigen::Matrix3d c = attitude();
  const double den = c(0, 0) * c(0, 0) + c(1, 0) * c(1, 0);
  if (den < 1e-12) return Eigen::RowVector3d(0, 0, 1);  // sensor x axis vertical
  return Eigen::RowVector3d(-c(0, 0) * c(2, 0) / den, -c(1, 0) * c(2, 0) / den, 1);
}

void ZuptFilter::Propagate(const Eigen::Vector3d& accel0, const Eigen::Vector3d& gyro0,
                           const Eigen::Vector3d& accel1, const Eigen::Vector3d& gyro1, double dt) {
  const Eigen::Vector3d w0 = gyro0 - bg_;
  const Eigen::Vector3d w1 = gyro1 - bg_;
  const Eigen::Matrix3d c0 = attitude();
  const Eigen::Vector3d f0 = c0 * (accel0 - ba_);
  const Eigen::Vector3d phi = 0.5 * (w0 + w1) * dt + w0.cross(w1) * (dt * dt / 12);
  q_ = (q_ * Exp(phi)).normalized();
  const Eigen::Matrix3d c1 = attitude();
  const Eigen::Vector3d f1 = c1 * (accel1 - ba_);
  const Eigen::Vector3d fn = 0.5 * (f0 + f1);
  const Eigen::Vector3d v0 = v_;
  v_ += (fn + Eigen::Vector3d(0, 0, -gravity_)) * dt;
  p_ += 0.5 * (v0 + v_) * dt;

  // P <- F P F^T + Q, F = I + dt A: A's nonzero blocks are dp/dv = I, dv/dtheta = -[fn x],
  // dv/dba = -C, dtheta/dbg = -C. Rows first (each block row reads rows not yet changed), then
  // columns the same way.
  const Eigen::Matrix3d c = 0.5 * (c0 + c1);
  const Eigen::Matrix3d m_vt = -dt * Skew(fn);
  const Eigen::Matrix3d m_c = -dt * c;
  Covariance& p = p_cov_;
  p.middleRows<3>(kP) += dt * p.middleRows<3>(kV);
  p.middleRows<3>(kV).noalias() += m_vt * p.middleRows<3>(kTheta);
  p.middleRows<3>(kV).noalias() += m_c * p.middleRows<3>(kBa);
  p.middleRows<3>(kTheta).noalias() += m_c * p.middleRows<3>(kBg);
  p.middleCols<3>(kP) += dt * p.middleCols<3>(kV);
  p.middleCols<3>(kV).noalias() += p.middleCols<3>(kTheta) * m_vt.transpose();
  p.middleCols<3>(kV).noalias() += p.middleCols<3>(kBa) * m_c.transpose();
  p.middleCols<3>(kTheta).noalias() += p.middleCols<3>(kBg) * m_c.transpose();
  // The noise is isotropic, so its navigation-frame covariance needs no rotation.
  p.block<3, 3>(kV, kV).diagonal().array() += noise_.accel * noise_.accel * dt;
  p.block<3, 3>(kTheta, kTheta).diagonal().array() += noise_.gyro * noise_.gyro * dt;
  p.block<3, 3>(kBa, kBa).diagonal().array() += noise_.accel_bias * noise_.accel_bias * dt;
  p.block<3, 3>(kBg, kBg).diagonal().array() += noise_.gyro_bias * noise_.gyro_bias * dt;
}

bool ZuptFilter::Update3(int first, const Eigen::Vector3d& y, double r, double gate) {
  Covariance& p = p_cov_;
  Eigen::Matrix3d s = p.block<3, 3>(first, first);
  s.diagonal().array() += r;
  const Eigen::Matrix3d s_inv = s.llt().solve(Eigen::Matrix3d::Identity());
  if (gate > 0 && y.dot(s_inv * y) > gate) return false;
  const Eigen::Matrix<double, kStates, 3> k = p.middleCols<3>(first) * s_inv;
  const Eigen::Matrix<double, 3, kStates> hp = p.middleRows<3>(first);
  p.noalias() -= k * hp;
  p = 0.5 * (p + p.transpose()).eval();
  Inject(k * y);
  return true;
}

// Still, 0 = v + dv: -v measures the velocity error dv.
void ZuptFilter::UpdateZeroVelocity(double sigma) { Update3(kV, -v_, sigma * sigma, 0); }

bool ZuptFilter::UpdateZeroAngularRate(const Eigen::Vector3d& gyro, double sigma) {
  // Still, the raw rate is the bias plus noise: gyro - bg measures the bias error dbg. A foot
  // that rolls while its velocity is zero is not still in rate: such samples fail the gate
  // (chi-square, 3 degrees of freedom, 0.1 %) and are skipped.
  constexpr double kGate = 16.27;
  return Update3(kBg, gyro - bg_, sigma * sigma, kGate);
}

void ZuptFilter::Inject(const Eigen::Matrix<double, kStates, 1>& dx) {
  p_ += dx.segment<3>(kP);
  v_ += dx.segment<3>(kV);
  q_ = (Exp(dx.segment<3>(kTheta)) * q_).normalized();
  ba_ += dx.segment<3>(kBa);
  bg_ += dx.segment<3>(kBg);
  clone_p_ += dx.segment<3>(kClone);
  clone_heading_ += dx(kClone + 3);
}

void ZuptFilter::Clone() {
  clone_p_ = p_;
  clone_heading_ = heading();
  // J maps the 15 navigation errors to the clone's: position, and heading through the attitude.
  Eigen::Matrix<double, 4, 15> j = Eigen::Matrix<double, 4, 15>::Zero();
  j.block<3, 3>(0, kP).setIdentity();
  j.block<1, 3>(3, kTheta) = HeadingJacobian();
  Covariance& p = p_cov_;
  const Eigen::Matrix<double, 4, 15> jp = j * p.topLeftCorner<15, 15>();
  p.block<4, 15>(kClone, 0) = jp;
  p.block<15, 4>(0, kClone) = jp.transpose();
  p.block<4, 4>(kClone, kClone) = jp * j.transpose();
}

StepDelta ZuptFilter::SinceClone() const {
  StepDelta d;
  d.position = p_ - clone_p_;
  d.heading = WrapAngle(heading() - clone_heading_);
  // L maps the error state to the errors of (dx, dy, dheading).
  Eigen::Matrix<double, 3, kStates> l = Eigen::Matrix<double, 3, kStates>::Zero();
  l(0, kP) = 1;
  l(1, kP + 1) = 1;
  l.block<1, 3>(2, kTheta) = HeadingJacobian();
  l(0, kClone) = -1;
  l(1, kClone + 1) = -1;
  l(2, kClone + 3) = -1;
  d.covariance = l * p_cov_ * l.transpose();
  return d;
}

}  // namespace grove::imu
