// RBF outage bridging (estimator/rbf_net.*, estimator/rbf_bridge.*, seed 004):
// the network reproduces a known function with an honest error variance, it is
// inert where untrained, and the bridge learns a standalone INS's drift.
// The Navigator-level tests are in tests/firmware/test_rbf_bridge_nav.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>

#include "estimator/rbf_bridge.hpp"
#include "estimator/rbf_net.hpp"

namespace uwbnav {
namespace {

// Deterministic uniform numbers in [0, 1) (64-bit LCG, top bits).
struct Lcg {
  uint64_t s = 0x9E3779B97F4A7C15ULL;
  Real next() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<Real>(static_cast<double>(s >> 11) / 9007199254740992.0);
  }
  Real gauss() {  // Box-Muller
    const Real u1 = std::fmax(next(), Real(1e-9));
    const Real u2 = next();
    return std::sqrt(Real(-2) * std::log(u1)) * std::cos(Real(2) * kPi * u2);
  }
};

// The known function: smooth in every input over the bridge's input domain.
RbfNet::Output known(const RbfNet::Input& x) {
  return RbfNet::Output(Real(0.2) * x(0) * x(0) + Real(0.3) * x(1), std::sin(x(0)) * (Real(0.5) + x(2)));
}

RbfNet::Input draw_input(Lcg& r, Real tau_max) {
  return RbfNet::Input(tau_max * r.next(), Real(0.25) + r.next(), Real(-0.5) + r.next());
}

RbfNet bridge_shaped_net() {
  const RbfBridge bridge;
  RbfNet net;
  net.configure(bridge.net().centres(), Real(0), RbfNet::Settings{});
  return net;
}

TEST(RbfNet, WidthFollowsSeed004Eq11FromTheCentreGrid) {
  const RbfNet net = bridge_shaped_net();
  // Grid 4 x 2 x 2, one unit apart: c_max = sqrt(3^2 + 1 + 1), h = 16.
  EXPECT_NEAR(static_cast<double>(net.width()), std::sqrt(11.0) / std::sqrt(32.0), 1e-5);
}

TEST(RbfNet, ReproducesAKnownFunctionWithAnHonestErrorVariance) {
  RbfNet net = bridge_shaped_net();
  Lcg r;
  const Real noise_m = Real(0.05);
  for (int i = 0; i < 30000; ++i) {
    const RbfNet::Input x = draw_input(r, Real(3));
    RbfNet::Output y = known(x);
    y(0) += noise_m * r.gauss();
    y(1) += noise_m * r.gauss();
    net.train(x, y);
  }
  double sq = 0.0, covered = 0.0, var_sum = 0.0;
  const int n = 400;
  for (int i = 0; i < n; ++i) {
    const RbfNet::Input x = draw_input(r, Real(3));
    const RbfNet::Prediction p = net.predict(x);
    ASSERT_TRUE(p.valid) << "x = " << x.transpose();
    const RbfNet::Output truth = known(x);
    for (int k = 0; k < 2; ++k) {
      const double e = static_cast<double>(p.y(k) - truth(k));
      sq += e * e;
      // A new noisy sample must fall within 2 sigma of the prediction ~95 % of the time.
      const double e_obs = e - static_cast<double>(noise_m * r.gauss());
      covered += std::fabs(e_obs) <= 2.0 * std::sqrt(static_cast<double>(p.var(k))) ? 1.0 : 0.0;
      var_sum += static_cast<double>(p.var(k));
    }
  }
  const double rmse = std::sqrt(sq / (2.0 * n));
  std::printf("known function: RMSE %.4f (noise 0.05), mean predicted sigma %.4f, in 2 sigma %.1f %%\n", rmse,
              std::sqrt(var_sum / (2.0 * n)), 100.0 * covered / (2.0 * n));
  EXPECT_LT(rmse, 0.04);  // the function's range is ~2.5: the network fits it to a fraction of the noise
  EXPECT_GE(covered / (2.0 * n), 0.90);
  EXPECT_LT(std::sqrt(var_sum / (2.0 * n)), 0.15);  // and the claim is not vacuous
}

TEST(RbfNet, UntrainedNetworkPredictsNothing) {
  const RbfNet net = bridge_shaped_net();
  const RbfNet::Prediction p = net.predict(RbfNet::Input(1, 0.5, 0));
  EXPECT_FALSE(p.valid);
  EXPECT_EQ(p.y(0), Real(0));
  EXPECT_EQ(p.y(1), Real(0));
}

TEST(RbfNet, NoPredictionWhereItWasNotTrained) {
  RbfNet net = bridge_shaped_net();
  Lcg r;
  for (int i = 0; i < 3000; ++i) {
    const RbfNet::Input x = draw_input(r, Real(0.8));  // coasts of up to 8 s only
    net.train(x, known(x));
  }
  EXPECT_TRUE(net.predict(RbfNet::Input(0.5, 0.75, 0)).valid);
  EXPECT_FALSE(net.predict(RbfNet::Input(2.5, 0.75, 0)).valid);  // 25 s: never seen
  EXPECT_FALSE(net.predict(RbfNet::Input(0.5, 9.0, 0)).valid);   // far outside every centre
}

TEST(RbfNet, NonFiniteSamplesAreIgnored) {
  RbfNet net = bridge_shaped_net();
  net.train(RbfNet::Input(std::nan(""), 0, 0), RbfNet::Output(1, 1));
  net.train(RbfNet::Input(1, 0.5, 0), RbfNet::Output(std::nan(""), 1));
  EXPECT_FALSE(net.trained());
}

// Straight drive at constant speed; the filter state is the truth, the IMU has
// an accelerometer bias the filter's state does not hold: every shadow drifts
// by -b tau^2 / 2 along x, which the network must learn and predict.
TEST(RbfBridge, LearnsTheDriftOfAStandaloneInsAndPredictsItInAnOutage) {
  RbfBridge bridge;
  bridge.configure(RbfMode::kOn);
  const Real g = Real(9.80665);
  const Real speed = Real(3);
  const Real bias = Real(0.02);  // along body x [m/s^2]
  const uint64_t dt_us = 10000;
  const Real dt = Real(0.01);
  NominalState x;
  x.vel_nav_mps = Vec3(speed, 0, 0);
  const Vec3 f(bias, 0, g);
  const Vec3 w = Vec3::Zero();
  uint64_t t = 1000000;
  RbfBridge::Correction c;
  const uint64_t train_until = t + 400000000;  // 400 s with fixes at 10 Hz
  for (; t < train_until; t += dt_us) {
    x.pos_nav_m.x() += speed * dt;
    if (t % 100000 == 0) bridge.on_fix(t, x);
    bridge.on_imu(t, f, w, dt, g, x, t - t % 100000);
  }
  EXPECT_GT(bridge.diag().train_samples, 1000U);
  // Outage: no fixes; predict 10 s and 20 s after the last fix.
  const uint64_t last_fix = t - dt_us;
  for (; t <= last_fix + 20000000; t += dt_us) {
    x.pos_nav_m.x() += speed * dt;
    bridge.on_imu(t, f, w, dt, g, x, last_fix);
    const Real tau = static_cast<Real>(t - last_fix) * Real(1e-6);
    if (t == last_fix + 10000000 || t == last_fix + 20000000) {
      ASSERT_TRUE(bridge.predict(t, c)) << "tau " << tau;
      const Real ex = c.pos_x_nav_m - x.pos_nav_m.x();
      const Real ey = c.pos_y_nav_m - x.pos_nav_m.y();
      const Real drift = Real(0.5) * bias * tau * tau;
      std::printf("tau %.0f s: uncorrected drift %.3f m, error after correction %.3f / %.3f m, sigma %.3f / %.3f m\n",
                  static_cast<double>(tau), static_cast<double>(drift), static_cast<double>(ex),
                  static_cast<double>(ey), std::sqrt(static_cast<double>(c.var_x_m2)),
                  std::sqrt(static_cast<double>(c.var_y_m2)));
      EXPECT_LT(std::fabs(ex), Real(0.1) * drift);
      EXPECT_LT(std::fabs(ey), Real(0.05));
      EXPECT_LE(std::fabs(ex), Real(3) * std::sqrt(c.var_x_m2) + Real(0.01));
    }
  }
}

TEST(RbfBridge, InertWhenUntrainedOrOff) {
  RbfBridge bridge;
  bridge.configure(RbfMode::kOn);
  NominalState x;
  bridge.on_fix(1000000, x);
  for (uint64_t t = 1010000; t < 5000000; t += 10000) {
    bridge.on_imu(t, Vec3(0, 0, Real(9.81)), Vec3::Zero(), Real(0.01), Real(9.81), x, 1000000);
  }
  RbfBridge::Correction c;
  EXPECT_FALSE(bridge.predict(5000000, c));  // an outage shadow, but nothing learnt
  EXPECT_EQ(bridge.diag().predictions, 0U);
  RbfBridge off;
  off.on_fix(1000000, x);
  EXPECT_FALSE(off.predict(2000000, c));
}

}  // namespace
}  // namespace uwbnav
