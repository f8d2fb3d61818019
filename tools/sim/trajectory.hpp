// Truth trajectory of the simulated platform: for a ground vehicle smooth
// analytic speed, heading and height profiles with suspension roll/pitch; for
// a multicopter a smooth 3-D position profile with the tilt its acceleration
// needs and an independent yaw; and the exact specific force and body rates.
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
  // Multicopter: one rest-to-rest position segment (hold, goto or eight).
  struct AirSegment {
    double t0_s = 0.0;
    double dur_s = 1.0;
    ManeuverKind kind = ManeuverKind::kHold;
    Eigen::Vector3d p0 = Eigen::Vector3d::Zero();  // position at the start [m]
    Eigen::Vector3d dp = Eigen::Vector3d::Zero();  // goto displacement [m]
    double eight_x_m = 0.0, eight_y_m = 0.0, eight_rot_rad = 0.0, eight_loops = 0.0;
  };
  struct YawSegment {
    double t0_s = 0.0;
    double dur_s = 1.0;
    double yaw0_rad = 0.0, dyaw_rad = 0.0;
  };
  void build_air(const Scenario& s, double end_s);
  // Position, velocity, acceleration of the multicopter at t_s.
  void air_motion(double t_s, Eigen::Vector3d& p, Eigen::Vector3d& v, Eigen::Vector3d& a) const;
  double air_yaw(double t_s, double* yaw_rate) const;
  // Body -> nav rotation: body z along the thrust (a + g z_nav), heading yaw.
  Eigen::Matrix3d air_attitude(double t_s) const;
  KinState at_air(uint64_t t_us) const;

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

  RouteKind kind_ = RouteKind::kVehicle;
  std::vector<AirSegment> air_segs_;
  std::vector<YawSegment> yaw_segs_;
  std::vector<Segment> segs_;
  std::vector<Eigen::Vector2d> grid_xy_;  // horizontal position at k * kGridUs
  double roll_gain_rad_per_mps2_ = 0.0;
  double pitch_gain_rad_per_mps2_ = 0.0;
  double gravity_mps2_ = 9.80665;
};

// True when the segment p->q crosses the axis-aligned box (slab test).
bool segment_hits_box(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Box& box);

}  // namespace uwbnav::sim
