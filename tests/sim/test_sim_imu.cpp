// Simulator IMU model: noiseless strapdown reproduces the truth, rest reads +g,
// noise statistics follow the configured figures.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tools/sim/simulator.hpp"

namespace uwbnav::sim {
namespace {

Eigen::Vector3d v3(const Vec3f& v) {
  return Eigen::Vector3d(static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z));
}

SimOutput run(const std::string& scenario, bool ideal_imu, uint64_t seed = 7) {
  SimOptions opt;
  opt.seed = seed;
  opt.ideal_imu = ideal_imu;
  SimOutput out;
  std::string err;
  EXPECT_EQ(simulate(scenario, opt, out, &err), Status::kOk) << err;
  return out;
}

// Strapdown mechanisation in the navigation frame (host, double): quaternion
// update by the exponential of the rotation vector (trapezoid rate plus the
// two-sample coning term), velocity by the trapezoid rule on the nav-frame
// acceleration, position by the exact rule for linearly varying acceleration.
struct Strapdown {
  Eigen::Quaterniond q;
  Eigen::Vector3d v;
  Eigen::Vector3d p;
  double g;

  Eigen::Vector3d acc_nav(const Eigen::Quaterniond& qq, const Eigen::Vector3d& f) const {
    return qq * f + Eigen::Vector3d(0.0, 0.0, -g);
  }

  void step(const ImuSample& a, const ImuSample& b) {
    const double dt = static_cast<double>(b.t_us - a.t_us) * 1e-6;
    const Eigen::Vector3d w0 = v3(a.gyro_body_radps);
    const Eigen::Vector3d w1 = v3(b.gyro_body_radps);
    const Eigen::Vector3d rot = 0.5 * (w0 + w1) * dt + (1.0 / 12.0) * w0.cross(w1) * dt * dt;
    const double angle = rot.norm();
    Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
    if (angle > 0.0) dq = Eigen::Quaterniond(Eigen::AngleAxisd(angle, rot / angle));
    const Eigen::Quaterniond q1 = (q * dq).normalized();
    const Eigen::Vector3d a0 = acc_nav(q, v3(a.accel_body_mps2));
    const Eigen::Vector3d a1 = acc_nav(q1, v3(b.accel_body_mps2));
    p += v * dt + (2.0 * a0 + a1) * dt * dt / 6.0;
    v += 0.5 * (a0 + a1) * dt;
    q = q1;
  }
};

double strapdown_error_after(const SimOutput& out, double seconds) {
  const TruthState& t0 = out.truth.front();
  Strapdown sd;
  sd.q = Eigen::Quaterniond(t0.q_nav_body[0], t0.q_nav_body[1], t0.q_nav_body[2], t0.q_nav_body[3]);
  sd.v = Eigen::Vector3d(t0.vel_nav_mps[0], t0.vel_nav_mps[1], t0.vel_nav_mps[2]);
  sd.p = Eigen::Vector3d(t0.pos_nav_m[0], t0.pos_nav_m[1], t0.pos_nav_m[2]);
  sd.g = static_cast<double>(out.rec.site.gravity_mps2);
  const uint64_t end_us = static_cast<uint64_t>(seconds * 1e6);
  size_t k = 0;
  while (k + 1 < out.rec.imu.size() && out.rec.imu[k + 1].t_us <= end_us) {
    sd.step(out.rec.imu[k], out.rec.imu[k + 1]);
    ++k;
  }
  EXPECT_EQ(out.rec.imu[k].t_us, end_us);
  const TruthState& tk = out.truth[k];
  const double err = (sd.p - Eigen::Vector3d(tk.pos_nav_m[0], tk.pos_nav_m[1], tk.pos_nav_m[2])).norm();
  std::printf("strapdown position error after %.0f s: %.3g m\n", seconds, err);
  return (sd.p - Eigen::Vector3d(tk.pos_nav_m[0], tk.pos_nav_m[1], tk.pos_nav_m[2])).norm();
}

TEST(SimImu, NoiselessStrapdownReproducesTruthWithin1cmAfter60sParkingLot) {
  // GIVEN the default scenario (stop, accelerations, braking, turns, S-bend) with an ideal IMU
  const SimOutput out = run("parking_nlos", true);
  ASSERT_GT(out.rec.imu.size(), 6000U);
  // WHEN the IMU stream is integrated alone for 60 s THEN it stays on the truth within 1 cm
  EXPECT_LT(strapdown_error_after(out, 60.0), 0.01);
}

TEST(SimImu, NoiselessStrapdownReproducesTruthWithin1cmAfter60sIndoorWithClimbs) {
  const SimOutput out = run("indoor3d", true);
  EXPECT_LT(strapdown_error_after(out, 60.0), 0.01);
}

TEST(SimImu, NoiselessStrapdownReproducesTruthWithin1cmAfter60sMulticopter) {
  // GIVEN the multicopter preset (take-off, figure-eight with tilt, waypoints, yaw turns)
  const SimOutput out = run("drone_indoor", true);
  // WHEN the IMU stream is integrated alone THEN it stays on the truth within 1 cm
  EXPECT_LT(strapdown_error_after(out, 60.0), 0.01);
}

TEST(SimImu, MulticopterTiltsIntoItsAccelerationAndFeelsThrustOnlyAlongBodyZ) {
  const SimOutput out = run("drone_indoor", true);
  double max_tilt = 0.0;
  for (const TruthState& t : out.truth) {
    const Eigen::Quaterniond q(t.q_nav_body[0], t.q_nav_body[1], t.q_nav_body[2], t.q_nav_body[3]);
    const Eigen::Vector3d a(t.acc_nav_mps2[0], t.acc_nav_mps2[1], t.acc_nav_mps2[2] + static_cast<double>(out.rec.site.gravity_mps2));
    // Body z is the thrust direction: the specific force has no body x/y part.
    EXPECT_LT(std::hypot(t.accel_body_mps2[0], t.accel_body_mps2[1]), 1e-9);
    EXPECT_LT((q * Eigen::Vector3d::UnitZ() - a.normalized()).norm(), 1e-8);
    max_tilt = std::max(max_tilt, std::acos(std::min(1.0, (q * Eigen::Vector3d::UnitZ()).z())));
  }
  EXPECT_GT(max_tilt, 2.0 * 3.14159265358979 / 180.0);
  EXPECT_LT(max_tilt, 35.0 * 3.14159265358979 / 180.0);
}

TEST(SimImu, TruthVelocityIsTheDerivativeOfTruthPosition) {
  const SimOutput out = run("parking_nlos", true);
  double worst = 0.0;
  for (size_t k = 1; k + 1 < 12000; ++k) {
    const double dt = static_cast<double>(out.truth[k + 1].t_us - out.truth[k - 1].t_us) * 1e-6;
    for (int i = 0; i < 3; ++i) {
      const double fd = (out.truth[k + 1].pos_nav_m[i] - out.truth[k - 1].pos_nav_m[i]) / dt;
      worst = std::max(worst, std::fabs(fd - out.truth[k].vel_nav_mps[i]));
    }
  }
  EXPECT_LT(worst, 1e-3);
}

TEST(SimImu, AtRestSpecificForceIsPlusGOnZAndRatesAreZero) {
  // GIVEN the parked start of the default scenario and an ideal IMU
  const SimOutput out = run("parking_nlos", true);
  const double g = static_cast<double>(out.rec.site.gravity_mps2);
  // THEN during the first 10 s the IMU reads exactly (0, 0, +g) and zero rates
  for (size_t k = 0; k < 1000; ++k) {
    const ImuSample& s = out.rec.imu[k];
    EXPECT_EQ(s.accel_body_mps2.x, 0.0F);
    EXPECT_EQ(s.accel_body_mps2.y, 0.0F);
    EXPECT_NEAR(static_cast<double>(s.accel_body_mps2.z), g, 1e-6);
    EXPECT_EQ(s.gyro_body_radps.x, 0.0F);
    EXPECT_EQ(s.gyro_body_radps.y, 0.0F);
    EXPECT_EQ(s.gyro_body_radps.z, 0.0F);
  }
}

TEST(SimImu, TurnsAndBrakingTiltTheBodyWithTheSuspensionSigns) {
  const SimOutput out = run("parking_nlos", true);
  bool saw_left_turn = false;
  bool saw_braking = false;
  for (const TruthState& t : out.truth) {
    const Eigen::Quaterniond q(t.q_nav_body[0], t.q_nav_body[1], t.q_nav_body[2], t.q_nav_body[3]);
    const Eigen::Matrix3d R = q.toRotationMatrix();
    const Eigen::Vector3d a_body = q.conjugate() * Eigen::Vector3d(t.acc_nav_mps2[0], t.acc_nav_mps2[1], 0.0);
    const double roll = std::atan2(R(2, 1), R(2, 2));  // Euler ZYX
    const double pitch = -std::asin(R(2, 0));
    if (a_body.y() > 2.0) {  // strong left turn: body rolls right (positive roll about x)
      saw_left_turn = true;
      EXPECT_GT(roll, 0.0);
    }
    if (a_body.x() < -1.5) {  // hard braking: nose dips (positive pitch about y in FLU)
      saw_braking = true;
      EXPECT_GT(pitch, 0.0);
    }
  }
  EXPECT_TRUE(saw_left_turn);
  EXPECT_TRUE(saw_braking);
}

TEST(SimImu, NoisyImuHasTurnOnBiasesOfTable1Size) {
  // Over many seeds the parked gyro mean (turn-on bias) has a 1-sigma near 0.5 deg/s
  // and the accelerometer x mean near 15 mg (seed 000 Table 1).
  double gyro_ss = 0.0;
  double accel_ss = 0.0;
  const int runs = 40;
  for (int s = 0; s < runs; ++s) {
    const SimOutput out = run("indoor3d", false, 1000 + static_cast<uint64_t>(s));
    double gx = 0.0;
    double ax = 0.0;
    const size_t n = 500;
    for (size_t k = 0; k < n; ++k) {
      gx += static_cast<double>(out.rec.imu[k].gyro_body_radps.x);
      ax += static_cast<double>(out.rec.imu[k].accel_body_mps2.x);
    }
    gyro_ss += std::pow(gx / n, 2);
    accel_ss += std::pow(ax / n, 2);
  }
  const double gyro_sigma_dps = std::sqrt(gyro_ss / runs) * 180.0 / M_PI;
  const double accel_sigma_mg = std::sqrt(accel_ss / runs) / 9.80665 * 1000.0;
  EXPECT_NEAR(gyro_sigma_dps, 0.5, 0.15);
  EXPECT_NEAR(accel_sigma_mg, 15.0, 4.5);
}

TEST(SimImu, NoisyParkedGyroNoiseMatchesAngleRandomWalk) {
  const SimOutput out = run("parking_nlos", false);
  // Sample-to-sample differences remove the bias: var(diff) = 2 sigma^2.
  double ss = 0.0;
  const size_t n = 1000;
  for (size_t k = 1; k <= n; ++k) {
    const double d = static_cast<double>(out.rec.imu[k].gyro_body_radps.z - out.rec.imu[k - 1].gyro_body_radps.z);
    ss += d * d;
  }
  const double sigma = std::sqrt(ss / n / 2.0);
  const double expected = 0.1 / 60.0 * M_PI / 180.0 * std::sqrt(100.0);  // ARW 0.1 deg/sqrt(h) at 100 Hz
  EXPECT_NEAR(sigma, expected, 0.15 * expected);
}

}  // namespace
}  // namespace uwbnav::sim
