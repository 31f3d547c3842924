// The strapdown INS of a foot-mounted IMU and its error-state Kalman filter with zero-velocity
// and zero-angular-rate pseudo-measurements (Foxlin 2005; Skog et al. 2010; Nilsson et al.,
// OpenShoe), and stochastic cloning of the pose at the end of each stance so that a step's
// displacement comes with its covariance (Roumeliotis and Burdick 2002).
//
// Frames: the navigation frame is local level, x and y horizontal, z up, gravity (0, 0, -g);
// C maps sensor-frame vectors into it. The accelerometer measures specific force f = a - g, so
// (0, 0, +g) in the navigation frame at rest.
//
// Error state (19): position, velocity, attitude (small angles in the navigation frame:
// C_true = (I + [dtheta x]) C), accelerometer bias, gyroscope bias (sensor frame), and the
// clone of position and heading at the last stance end. Errors are true minus estimate.
#ifndef GROVE_ENGINE_IMU_ZUPT_FILTER_H_
#define GROVE_ENGINE_IMU_ZUPT_FILTER_H_

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace grove::imu {

// Normal gravity of the WGS-84 ellipsoid (Somigliana's formula) at a geodetic latitude, less
// the free-air gradient of 3.086e-6 s^-2 per metre of height.
double NormalGravity(double latitude_rad, double height_m);

// The rotation from the sensor frame to the navigation frame of z-y-x Euler angles
// (Rz(yaw) Ry(pitch) Rx(roll)), and back.
Eigen::Matrix3d RotationFromEuler(double roll, double pitch, double yaw);
Eigen::Vector3d EulerFromRotation(const Eigen::Matrix3d& c);  // roll, pitch, yaw
// Roll and pitch of a still sensor measuring the specific force `f`.
Eigen::Vector2d TiltFromSpecificForce(const Eigen::Vector3d& f);

struct FilterNoise {
  double accel = 0;       // white noise density, m/s^2/sqrt(Hz)
  double gyro = 0;        // rad/s/sqrt(Hz)
  double accel_bias = 0;  // bias random walk, m/s^3/sqrt(Hz)
  double gyro_bias = 0;   // rad/s^2/sqrt(Hz)
};

struct InitialSigmas {
  double velocity = 0;  // m/s
  double tilt = 0;      // rad
  double heading = 0;   // rad
  double accel_bias = 0;
  double gyro_bias = 0;
};

// A step: the change of position and heading since the clone, and its covariance over
// (dx, dy, dheading).
struct StepDelta {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double heading = 0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

class ZuptFilter {
 public:
  static constexpr int kStates = 19;
  using Covariance = Eigen::Matrix<double, kStates, kStates>;

  ZuptFilter(const FilterNoise& noise, double gravity) : noise_(noise), gravity_(gravity) {}

  // Starts still at the origin with the given attitude and gyroscope bias; the clone is the
  // start.
  void Start(const Eigen::Matrix3d& attitude, const Eigen::Vector3d& gyro_bias,
             const InitialSigmas& sigmas);

  // Integrates from the previous sample (accel0, gyro0, raw) to the next (accel1, gyro1) over
  // dt seconds: trapezoidal rates with a coning term, trapezoidal specific force and velocity.
  void Propagate(const Eigen::Vector3d& accel0, const Eigen::Vector3d& gyro0,
                 const Eigen::Vector3d& accel1, const Eigen::Vector3d& gyro1, double dt);
  // Velocity is zero (m/s sigma).
  void UpdateZeroVelocity(double sigma);
  // The angular rate `gyro` (raw) is zero (rad/s sigma); false, nothing changed, when the
  // innovation fails the gate.
  bool UpdateZeroAngularRate(const Eigen::Vector3d& gyro, double sigma);

  // Clones position and heading: the start of the next step.
  void Clone();
  StepDelta SinceClone() const;

  const Eigen::Vector3d& position() const { return p_; }
  const Eigen::Vector3d& velocity() const { return v_; }
  Eigen::Matrix3d attitude() const { return q_.toRotationMatrix(); }
  double heading() const;
  const Eigen::Vector3d& accel_bias() const { return ba_; }
  const Eigen::Vector3d& gyro_bias() const { return bg_; }
  const Covariance& covariance() const { return p_cov_; }

 private:
  // Applies the correction dx (all states) and resets the error to zero.
  void Inject(const Eigen::Matrix<double, kStates, 1>& dx);
  // The 1 x 3 derivative of heading with respect to the attitude error.
  Eigen::RowVector3d HeadingJacobian() const;
  // Kalman update with a 3-row measurement of the states at `first` (selection matrix), the
  // innovation `y` and noise variance `r`; refused (false) when the normalised innovation
  // squared exceeds `gate` > 0.
  bool Update3(int first, const Eigen::Vector3d& y, double r, double gate);

  FilterNoise noise_;
  double gravity_;
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();  // sensor to navigation
  Eigen::Vector3d ba_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d clone_p_ = Eigen::Vector3d::Zero();
  double clone_heading_ = 0;
  Covariance p_cov_ = Covariance::Zero();
};

}  // namespace grove::imu

#endif  // GROVE_ENGINE_IMU_ZUPT_FILTER_H_
