// EKF core: block-sparse covariance propagation equals the dense Phi P Phi^T + Q,
// mechanisation at rest stays put, updates shrink variance and refuse
// non-finite input, sanitise detects explosions and clamps variances.
#include <gtest/gtest.h>

#include <cmath>

#include "estimator/ekf_core.hpp"

namespace uwbnav {
namespace {

constexpr double kTolRel = sizeof(Real) == sizeof(float) ? 1e-4 : 1e-10;

ErrCov random_spd(unsigned seed) {
  std::srand(seed);
  ErrCov a = ErrCov::Random();
  ErrCov p = a * a.transpose() * Real(0.1) + ErrCov::Identity() * Real(0.01);
  return p;
}

TEST(EkfCore, SparsePropagationEqualsDenseTransition) {
  EkfCore ekf;
  NominalState x;
  x.q_nav_body = quat_normalised(Quat(Real(0.95), Real(0.1), Real(-0.05), Real(0.3)));
  x.ba_body_mps2 = Vec3(Real(0.1), Real(-0.05), Real(0.02));
  ekf.init(x, ErrVec::Ones());
  ekf.mutable_cov() = random_spd(3);
  const ErrCov p0 = ekf.cov();
  const Vec3 f(Real(1.2), Real(-0.4), Real(9.9));
  const Vec3 w(Real(0.1), Real(0.05), Real(-0.3));
  const Real dt = Real(0.01);
  ImuNoise noise;
  // Dense reference built from the same mid-interval quantities.
  const Quat q_mid = quat_mul(x.q_nav_body, quat_exp((w - x.bg_body_radps) * (Real(0.5) * dt)));
  const Mat3 c = quat_to_dcm(q_mid);
  const Vec3 f_nav = c * (f - x.ba_body_mps2);
  ErrCov a = ErrCov::Zero();
  a.block<3, 3>(ErrIdx::kPos, ErrIdx::kVel) = Mat3::Identity();
  a.block<3, 3>(ErrIdx::kVel, ErrIdx::kAtt) = -skew(f_nav);
  a.block<3, 3>(ErrIdx::kVel, ErrIdx::kBa) = -c;
  a.block<3, 3>(ErrIdx::kAtt, ErrIdx::kBg) = -c;
  const ErrCov ad = a * dt;
  const ErrCov phi = ErrCov::Identity() + ad + ad * ad / Real(2) + ad * ad * ad / Real(6);
  ErrCov q = ErrCov::Zero();
  const Real qa = noise.accel_noise * noise.accel_noise;
  for (int i = 0; i < 3; ++i) {
    q(i, i) = qa * dt * dt * dt / Real(3);
    q(i, 3 + i) = q(3 + i, i) = qa * dt * dt / Real(2);
    q(3 + i, 3 + i) = qa * dt;
    q(6 + i, 6 + i) = noise.gyro_noise * noise.gyro_noise * dt;
    q(9 + i, 9 + i) = noise.accel_bias_rw * noise.accel_bias_rw * dt;
    q(12 + i, 12 + i) = noise.gyro_bias_rw * noise.gyro_bias_rw * dt;
  }
  const ErrCov expected = phi * p0 * phi.transpose() + q;
  ekf.predict_imu(f, w, dt, Real(9.80665), noise);
  const double scale = static_cast<double>(expected.cwiseAbs().maxCoeff());
  EXPECT_LT(static_cast<double>((ekf.cov() - expected).cwiseAbs().maxCoeff()), kTolRel * scale * 10);
}

TEST(EkfCore, AMeasuredTurnRotatesTheRangesOnlyVelocityHeadingAndTheirCovarianceAsFPFt) {
  // GIVEN a ranges-only state moving east at 2 m/s with a random covariance
  EkfCore ekf;
  NominalState x;
  x.vel_nav_mps = Vec3(Real(2), Real(0), Real(0.1));
  x.q_nav_body = quat_normalised(quat_mul(quat_from_yaw(Real(0.3)), Quat(Real(0.99), Real(0.05), Real(-0.03), Real(0))));
  ekf.init(x, ErrVec::Ones());
  ekf.mutable_cov() = random_spd(7);
  const ErrCov p0 = ekf.cov();
  const Real turn = Real(0.4);
  // WHEN the gyro's turn of 0.4 rad about the vertical is applied over a zero-length step
  ekf.predict_cv(Real(0), Real(0), Real(0), Real(0), Real(0), turn);
  // THEN the velocity turned by 0.4 rad (speed and vertical kept), the yaw by 0.4 rad
  // with the tilt unchanged, and P became F P F^T with F rotating the (v_x, v_y)
  // and nav-frame (theta_x, theta_y) error pairs: the same error, seen after the turn
  const Real c = std::cos(turn), s = std::sin(turn);
  EXPECT_NEAR(static_cast<double>(ekf.state().vel_nav_mps.x()), static_cast<double>(2 * c), 1e-5);
  EXPECT_NEAR(static_cast<double>(ekf.state().vel_nav_mps.y()), static_cast<double>(2 * s), 1e-5);
  EXPECT_NEAR(static_cast<double>(ekf.state().vel_nav_mps.z()), 0.1, 1e-6);
  const Quat q_expected = quat_normalised(quat_mul(quat_from_yaw(turn), x.q_nav_body));
  EXPECT_LT(static_cast<double>((ekf.state().q_nav_body - q_expected).cwiseAbs().maxCoeff()), 1e-6);
  EXPECT_NEAR(static_cast<double>(wrap_pi(quat_yaw(ekf.state().q_nav_body) - quat_yaw(x.q_nav_body))),
              static_cast<double>(turn), 1e-5);
  ErrCov f = ErrCov::Identity();
  for (int i : {ErrIdx::kVel, ErrIdx::kAtt}) {
    f(i, i) = c;
    f(i, i + 1) = -s;
    f(i + 1, i) = s;
    f(i + 1, i + 1) = c;
  }
  const ErrCov expected = f * p0 * f.transpose();
  const double scale = static_cast<double>(expected.cwiseAbs().maxCoeff());
  EXPECT_LT(static_cast<double>((ekf.cov() - expected).cwiseAbs().maxCoeff()), kTolRel * scale * 10);
  EXPECT_LT(static_cast<double>((ekf.cov() - ekf.cov().transpose()).cwiseAbs().maxCoeff()), kTolRel * scale);
}

TEST(EkfCore, AMeasuredTurnOverAStepMovesThePositionAlongTheMidpointVelocity) {
  // GIVEN a ranges-only state moving east at 2 m/s, heading past +180 deg after the turn
  EkfCore ekf;
  NominalState x;
  x.vel_nav_mps = Vec3(Real(2), Real(0), Real(0));
  x.q_nav_body = quat_from_yaw(Real(2.9));
  ekf.init(x, ErrVec::Ones());
  // WHEN a 1 s step carries a measured turn of 0.8 rad (no process noise)
  const Real turn = Real(0.8);
  ekf.predict_cv(Real(1), Real(0), Real(0), Real(0), Real(0), turn);
  // THEN the position moved along the velocity turned by half the turn (the
  // arc's midpoint chord), the velocity ends turned by all of it, and the
  // quaternion keeps its scalar non-negative past +-180 deg of yaw
  const Real h = Real(0.5) * turn;
  EXPECT_NEAR(static_cast<double>(ekf.state().pos_nav_m.x()), static_cast<double>(2 * std::cos(h)), 1e-5);
  EXPECT_NEAR(static_cast<double>(ekf.state().pos_nav_m.y()), static_cast<double>(2 * std::sin(h)), 1e-5);
  EXPECT_NEAR(static_cast<double>(ekf.state().vel_nav_mps.x()), static_cast<double>(2 * std::cos(turn)), 1e-5);
  EXPECT_NEAR(static_cast<double>(ekf.state().vel_nav_mps.y()), static_cast<double>(2 * std::sin(turn)), 1e-5);
  EXPECT_GE(static_cast<double>(ekf.state().q_nav_body(0)), 0.0);
  EXPECT_NEAR(static_cast<double>(wrap_pi(quat_yaw(ekf.state().q_nav_body) - Real(2.9) - turn)), 0.0, 1e-5);
}

TEST(EkfCore, LevelVehicleAtRestStaysPut) {
  EkfCore ekf;
  NominalState x;
  x.pos_nav_m = Vec3(Real(5), Real(6), Real(0));
  x.q_nav_body = quat_from_yaw(Real(0.7));
  ekf.init(x, ErrVec::Constant(Real(0.1)));
  for (int k = 0; k < 1000; ++k) {
    ekf.predict_imu(Vec3(Real(0), Real(0), Real(9.80665)), Vec3::Zero(), Real(0.01), Real(9.80665), ImuNoise{});
  }
  EXPECT_LT(static_cast<double>((ekf.state().pos_nav_m - x.pos_nav_m).norm()), 1e-3);
  EXPECT_LT(static_cast<double>(ekf.state().vel_nav_mps.norm()), 1e-4);
  EXPECT_NEAR(static_cast<double>(quat_yaw(ekf.state().q_nav_body)), 0.7, 1e-5);
  // Covariance grows (coasting) and is exactly symmetric after sanitise().
  EXPECT_GT(ekf.cov()(0, 0), Real(0.01));
  ASSERT_TRUE(ekf.sanitise());
  EXPECT_EQ(static_cast<double>((ekf.cov() - ekf.cov().transpose()).cwiseAbs().maxCoeff()), 0.0);
  const Eigen::SelfAdjointEigenSolver<ErrCov> es(ekf.cov(), Eigen::EigenvaluesOnly);
  // Positive semi-definite up to the precision's rounding relative to the largest eigenvalue.
  EXPECT_GT(es.eigenvalues()(0), -Real(1e-5) * es.eigenvalues()(kN - 1));
}

TEST(EkfCore, ConstantRateRotationIntegratesExactly) {
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Constant(Real(0.1)));
  const Real rate = Real(0.5);  // rad/s about z
  for (int k = 0; k < 200; ++k) {
    ekf.predict_imu(Vec3(Real(0), Real(0), Real(9.80665)), Vec3(Real(0), Real(0), rate), Real(0.01), Real(9.80665),
                    ImuNoise{});
  }
  EXPECT_NEAR(static_cast<double>(quat_yaw(ekf.state().q_nav_body)), 1.0, 1e-4);
}

TEST(EkfCore, ScalarUpdateShrinksVarianceAndCorrectsState) {
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Ones());
  ScalarObs obs;
  obs.h(ErrIdx::kPos) = Real(1);
  obs.innovation = Real(0.5);
  obs.r_var = Real(1);
  const UpdateResult r = ekf.update(obs);
  EXPECT_TRUE(r.applied);
  EXPECT_NEAR(static_cast<double>(r.innovation_var), 2.0, 1e-6);
  EXPECT_NEAR(static_cast<double>(ekf.cov()(0, 0)), 0.5, 1e-6);
  EXPECT_NEAR(static_cast<double>(ekf.state().pos_nav_m.x()), 0.25, 1e-6);
}

TEST(EkfCore, ConsiderUpdateOfACoreObservationLeavesCorrelatedRangeErrorsAlone) {
  // A height-like observation of z, with z correlated with an anchor offset
  // (as consider range updates leave them): the full update moves the offset
  // through the correlation, the consider update moves only the core states
  // and keeps the offset's own variance, as Navigator::fuse needs for the
  // ranges-only filter's pseudo-measurements.
  EkfCore full;
  full.init(NominalState{}, ErrVec::Ones());
  const int z = ErrIdx::kPos + 2;
  const int off = ErrIdx::kAnchorBias;
  full.mutable_cov()(z, off) = Real(0.8);
  full.mutable_cov()(off, z) = Real(0.8);
  EkfCore consider = full;
  ScalarObs obs;
  obs.h(z) = Real(1);
  obs.innovation = Real(-0.3);
  obs.r_var = Real(0.01);
  ASSERT_TRUE(full.update(obs).applied);
  ASSERT_TRUE(consider.update(obs, true).applied);
  EXPECT_LT(full.state().anchor_bias_m(0), Real(-0.2));
  EXPECT_EQ(consider.state().anchor_bias_m(0), Real(0));
  EXPECT_EQ(consider.cov()(off, off), Real(1));
  EXPECT_NEAR(static_cast<double>(consider.state().pos_nav_m.z()), static_cast<double>(full.state().pos_nav_m.z()), 1e-6);
  EXPECT_LT(consider.cov()(z, z), Real(0.02));
}

TEST(EkfCore, NonFiniteObservationIsRefused) {
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Ones());
  ScalarObs obs;
  obs.h(0) = Real(1);
  obs.innovation = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_FALSE(ekf.update(obs).applied);
  obs.innovation = Real(1);
  obs.r_var = -Real(5);  // S would be negative
  EXPECT_FALSE(ekf.update(obs).applied);
  EXPECT_TRUE(ekf.cov().allFinite());
  EXPECT_TRUE(ekf.sanitise());
}

TEST(EkfCore, SanitiseDetectsExplosionAndClampsVariances) {
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Ones());
  ekf.mutable_cov()(0, 0) = Real(1e9);
  ekf.mutable_cov()(6, 6) = Real(0);
  EXPECT_TRUE(ekf.sanitise());
  EXPECT_LE(ekf.cov()(0, 0), Real(1e6) * Real(1.0001));
  EXPECT_GT(ekf.cov()(6, 6), Real(0));
  ekf.mutable_state().vel_nav_mps.x() = Real(1e5);
  EXPECT_FALSE(ekf.sanitise());
  ekf.mutable_state().vel_nav_mps.x() = std::numeric_limits<Real>::infinity();
  EXPECT_FALSE(ekf.sanitise());
}

}  // namespace
}  // namespace uwbnav
