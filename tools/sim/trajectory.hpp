// Truth trajectory of the simulated ground vehicle: smooth analytic speed,
// heading and height profiles from the scenario route, suspension roll/pitch,
// and the exact specific force and body rates they imply.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tools/sim/scenario.hpp"

namespace uwbnav::sim {

// Full kinematic truth of the body origin at one instant.
struct KinState {
  Eigen::Vector3d pos_nav_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d vel_nav_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_nav_mps2 = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_nav_body = Eigen::Quaterniond::Identity();  // body -> nav
  Eigen::Matrix3d R_nav_body = Eigen::Matrix3d::Identity();
  Eigen::Vector3d gyro_body_radps = Eigen::Vector3d::Zero();   // true body rate
  Eigen::Vector3d accel_body_mps2 = Eigen::Vector3d::Zero();   // true specific force R^T (a - g_nav)
  double roll_rad = 0.0;   // about body x (FLU), Euler ZYX
  double pitch_rad = 0.0;  // about body y
  double yaw_rad = 0.0;    // about nav z, CCW from nav x
  double speed_mps = 0.0;  // along-path speed
};

class Trajectory {
 public:
  // Expands the route (looping from route.loop_from) to cover [0, end_s].
  void build(const Scenario& s, double end_s);

  // Truth at t_us (any microsecond, not only IMU instants).
  KinState at(uint64_t t_us) const;

 private:
  struct Segment {
    double t0_s = 0.0;
    double dur_s = 1.0;
    ManeuverKind kind = ManeuverKind::kHold;
    double v0_mps = 0.0, dv_mps = 0.0;
    double yaw0_rad = 0.0, dyaw_rad = 0.0;
    double z0_m = 0.0, dz_m = 0.0;
  };
  // Along-path speed, heading and height with their derivatives.
  struct Motion {
    double v = 0, a_lon = 0, jerk = 0;
    double yaw = 0, yaw_rate = 0, yaw_acc = 0;
    double z = 0, vz = 0, az = 0;
  };
  Motion motion(double t_s) const;
  Eigen::Vector2d integrate_xy(uint64_t t0_us, uint64_t t1_us) const;

  static constexpr uint64_t kGridUs = 10000;  // stored position grid [us]
  static constexpr uint64_t kStepUs = 2000;   // quadrature sub-step [us]

  std::vector<Segment> segs_;
  std::vector<Eigen::Vector2d> grid_xy_;  // horizontal position at k * kGridUs
  double roll_gain_rad_per_mps2_ = 0.0;
  double pitch_gain_rad_per_mps2_ = 0.0;
  double gravity_mps2_ = 9.80665;
};

// True when the segment p->q crosses the axis-aligned box (slab test).
bool segment_hits_box(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Box& box);

}  // namespace uwbnav::sim
