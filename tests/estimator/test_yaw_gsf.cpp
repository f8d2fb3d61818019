// Yaw Gaussian-sum bank (estimator/yaw_gsf.*) on simulated drives with the
// true roll/pitch and an unknown start yaw: it must find the yaw from single
// ranges and claim a yaw sigma that covers its error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "estimator/yaw_gsf.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

Quat quat_of(const double q[4]) {
  return Quat(static_cast<Real>(q[0]), static_cast<Real>(q[1]), static_cast<Real>(q[2]), static_cast<Real>(q[3]));
}

struct BankRun {
  Real yaw_error_rad = Real(10);
  Real yaw_sigma_rad = Real(10);
  int updates = 0;
};

// Runs the bank on the true levelled attitude (true roll/pitch, true yaw minus
// the unknown start yaw) from t_start_s; stops when its yaw sigma is below
// stop_sigma or at the end.
BankRun run_bank(const sim::SimOutput& so, double t_start_s, Real stop_sigma) {
  BankRun out;
  YawGsf bank;
  const auto& tr = so.truth;
  const auto& rec = so.rec;
  const Real yaw0_true = quat_yaw(quat_of(tr.front().q_nav_body));
  const Quat q_unyaw = quat_from_yaw(-yaw0_true);
  size_t j = 0;
  while (j < rec.uwb.size() && static_cast<double>(rec.uwb[j].range.t_us) * 1e-6 < t_start_s) ++j;
  YawGsf::Noise noise;
  for (size_t i = 1; i < tr.size(); ++i) {
    const double t = static_cast<double>(tr[i].t_us) * 1e-6;
    if (t < t_start_s) continue;
    const Quat q_lvl = quat_mul(q_unyaw, quat_of(tr[i - 1].q_nav_body));
    const Mat3 c = quat_to_dcm(q_lvl);
    if (!bank.active()) {
      const Vec3 tag(static_cast<Real>(tr[i].pos_nav_m[0]), static_cast<Real>(tr[i].pos_nav_m[1]),
                     static_cast<Real>(tr[i].pos_nav_m[2]));
      const Vec3 lev = to_vec3(rec.site.tags[0].lever_body_m);
      bank.start(tag + quat_to_dcm(quat_of(tr[i].q_nav_body)) * lev, c * lev, Real(0), Real(0.2), Real(0.3),
                 Real(1));
    }
    const Vec3 f(static_cast<Real>(rec.imu[i - 1].accel_body_mps2.x), static_cast<Real>(rec.imu[i - 1].accel_body_mps2.y),
                 static_cast<Real>(rec.imu[i - 1].accel_body_mps2.z));
    const Real dt = static_cast<Real>(tr[i].t_us - tr[i - 1].t_us) * Real(1e-6);
    bank.accumulate(c * f, dt);
    while (j < rec.uwb.size() && rec.uwb[j].range.t_us <= tr[i].t_us) {
      const UwbRange& r = rec.uwb[j++].range;
      bank.propagate(static_cast<Real>(rec.site.gravity_mps2), noise);
      const int ai = rec.site.find_anchor(r.anchor_id);
      const int ti = rec.site.find_tag(r.tag_id);
      (void)bank.update_range(to_vec3(rec.site.anchors[ai].pos_nav_m), c * to_vec3(rec.site.tags[ti].lever_body_m),
                              static_cast<Real>(r.range_m), Real(0.1));
    }
    out.yaw_error_rad = wrap_pi(bank.yaw_mean() - yaw0_true);
    out.yaw_sigma_rad = bank.yaw_sigma();
    out.updates = bank.updates();
    if (out.updates >= 10 && out.yaw_sigma_rad < stop_sigma) break;
  }
  return out;
}

TEST(YawGsf, FindsTheStartYawOfAGroundVehicleFromRangesAlone) {
  for (uint64_t seed : {31U, 32U}) {
    sim::SimOutput so;
    std::string err;
    sim::SimOptions opt;
    opt.seed = seed;
    ASSERT_EQ(sim::simulate("parking_los", opt, so, &err), Status::kOk) << err;
    const BankRun r = run_bank(so, 11.0, Real(0.1));
    std::printf("parking_los seed %llu: yaw error %.3f rad, claimed sigma %.3f rad after %d ranges\n",
                static_cast<unsigned long long>(seed), static_cast<double>(r.yaw_error_rad),
                static_cast<double>(r.yaw_sigma_rad), r.updates);
    EXPECT_LT(r.yaw_sigma_rad, Real(0.1));
    EXPECT_LT(std::fabs(r.yaw_error_rad), Real(3) * r.yaw_sigma_rad + Real(0.02));
  }
}

}  // namespace
}  // namespace uwbnav
