// Analytic Jacobians of every measurement model (range with lever arm, time
// offset, scale error, tag and anchor offsets; NHC, ZUPT/ZARU, height; GNSS
// antenna position and velocity with lever arm and latency) against
// central differences of the nominal model under error injection; singular
// range geometry stays finite.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "error_injection.hpp"
#include "estimator/mm_gnss.hpp"
#include "estimator/mm_height.hpp"
#include "estimator/mm_nhc.hpp"
#include "estimator/mm_position.hpp"
#include "estimator/mm_range.hpp"
#include "estimator/mm_zupt.hpp"

namespace uwbnav {
namespace {

using test::inject;

// Central-difference Jacobian of h(x) w.r.t. the error state.
ErrRow numeric_jacobian(const NominalState& x, const std::function<double(const NominalState&)>& h) {
  ErrRow j;
  const Real eps = sizeof(Real) == sizeof(float) ? Real(1e-3) : Real(1e-6);
  for (int i = 0; i < kN; ++i) {
    ErrVec dx = ErrVec::Zero();
    dx(i) = eps;
    const double hp = h(inject(x, dx));
    dx(i) = -eps;
    const double hm = h(inject(x, dx));
    j(i) = static_cast<Real>((hp - hm) / (2.0 * static_cast<double>(eps)));
  }
  return j;
}

NominalState sample_state() {
  NominalState x;
  x.pos_nav_m = Vec3(Real(12.5), Real(-3.25), Real(0.4));
  x.vel_nav_mps = Vec3(Real(3.1), Real(-1.2), Real(0.15));
  x.q_nav_body = quat_normalised(Quat(Real(0.9), Real(0.05), Real(-0.08), Real(0.42)));
  x.ba_body_mps2 = Vec3(Real(0.05), Real(-0.1), Real(0.02));
  x.bg_body_radps = Vec3(Real(0.004), Real(-0.003), Real(0.006));
  x.range_err(0) = Real(0.002);                                           // scale
  x.range_err(ErrIdx::kTagBias - ErrIdx::kCore + 1) = Real(0.07);         // tag 1 offset
  x.range_err(ErrIdx::kAnchorBias - ErrIdx::kCore + 2) = Real(-0.11);     // anchor slot 2 offset
  return x;
}

void expect_row_near(const ErrRow& analytic, const ErrRow& numeric, double tol) {
  for (int i = 0; i < kN; ++i) {
    EXPECT_NEAR(static_cast<double>(analytic(i)), static_cast<double>(numeric(i)), tol) << "column " << i;
  }
}

const double kTol = sizeof(Real) == sizeof(float) ? 2e-3 : 1e-6;

RangeErrorSlots slots_tag1_anchor2() {
  RangeErrorSlots es;
  es.tag_index = 1;
  es.anchor_slot = 2;
  es.known_offset_m = Real(0.25);
  return es;
}

TEST(MmRange, JacobianWithLeverArmTimeOffsetScaleAndOffsetsMatchesNumeric) {
  const NominalState x = sample_state();
  const Vec3 gyro(Real(0.3), Real(-0.2), Real(0.8));
  const Vec3 lever(Real(0.5), Real(-0.3), Real(1.7));
  const Vec3 anchor(Real(0), Real(0), Real(1.5));
  const Real dt = Real(0.007);
  const RangeErrorSlots es = slots_tag1_anchor2();
  const RangePrediction p = mm_range_predict(x, quat_to_dcm(x.q_nav_body), gyro, lever, anchor, dt, es);
  ASSERT_TRUE(p.valid);
  const ErrRow num = numeric_jacobian(x, [&](const NominalState& y) {
    return static_cast<double>(mm_range_predict(y, quat_to_dcm(y.q_nav_body), gyro, lever, anchor, dt, es).range_m);
  });
  expect_row_near(p.h, num, kTol);
  // The velocity column carries the time offset; attitude columns the lever arm;
  // the scale column the distance; exactly the two offset states the range reads.
  EXPECT_GT(p.h.segment<3>(ErrIdx::kVel).norm(), Real(0));
  EXPECT_GT(p.h.segment<3>(ErrIdx::kAtt).norm(), Real(0.1));
  EXPECT_NEAR(static_cast<double>(p.h(ErrIdx::kScale)), static_cast<double>(p.geometric_m), 1e-5);
  EXPECT_EQ(p.h.tail<ErrIdx::kRange - 1>().sum(), Real(2));
  EXPECT_EQ(p.h(ErrIdx::kTagBias + 1), Real(1));
  EXPECT_EQ(p.h(ErrIdx::kAnchorBias + 2), Real(1));
}

TEST(MmRange, RangeErrorsAddToTheGeometricDistance) {
  NominalState x;
  x.range_err(0) = Real(0.001);
  x.range_err(ErrIdx::kTagBias - ErrIdx::kCore + 1) = Real(0.05);
  x.range_err(ErrIdx::kAnchorBias - ErrIdx::kCore + 2) = Real(0.1);
  const Vec3 anchor(Real(30), Real(40), Real(0));  // 50 m away
  const RangePrediction p = mm_range_predict(x, Mat3::Identity(), Vec3::Zero(), Vec3::Zero(), anchor, Real(0),
                                             slots_tag1_anchor2());
  ASSERT_TRUE(p.valid);
  EXPECT_NEAR(static_cast<double>(p.geometric_m), 50.0, 1e-4);
  // (1 + 0.001) 50 + 0.05 + 0.1 + 0.25 (commissioned)
  EXPECT_NEAR(static_cast<double>(p.range_m), 50.05 + 0.05 + 0.1 + 0.25, 1e-4);
  // Without slots only the geometry (and the scale) counts.
  RangeErrorSlots none;
  none.scale = false;
  const RangePrediction g = mm_range_predict(x, Mat3::Identity(), Vec3::Zero(), Vec3::Zero(), anchor, Real(0), none);
  EXPECT_NEAR(static_cast<double>(g.range_m), 50.0, 1e-4);
  EXPECT_EQ(g.h.tail<ErrIdx::kRange>().squaredNorm(), Real(0));
}

TEST(MmRange, PredictsTagAtTheRangeTimeNotTheStateTime) {
  NominalState x;
  x.vel_nav_mps = Vec3(Real(10), Real(0), Real(0));
  const Vec3 anchor(Real(100), Real(0), Real(0));
  const RangeErrorSlots es;
  const RangePrediction now = mm_range_predict(x, Mat3::Identity(), Vec3::Zero(), Vec3::Zero(), anchor, Real(0), es);
  const RangePrediction later =
      mm_range_predict(x, Mat3::Identity(), Vec3::Zero(), Vec3::Zero(), anchor, Real(0.008), es);
  EXPECT_NEAR(static_cast<double>(now.range_m - later.range_m), 0.08, 1e-4);  // 10 m/s * 8 ms closer
}

TEST(MmRange, TagOnTheAnchorIsInvalidAndFinite) {
  NominalState x;
  x.pos_nav_m = Vec3(Real(1), Real(2), Real(0));
  const Vec3 lever(Real(0), Real(0), Real(1.5));
  const RangePrediction p = mm_range_predict(x, Mat3::Identity(), Vec3::Zero(), lever,
                                             Vec3(Real(1), Real(2), Real(1.5)), Real(0), slots_tag1_anchor2());
  EXPECT_FALSE(p.valid);
  EXPECT_TRUE(p.h.allFinite());
  EXPECT_TRUE(std::isfinite(p.range_m));
}

TEST(MmNhc, LateralAndVerticalJacobiansMatchNumeric) {
  const NominalState x = sample_state();
  for (int axis = 1; axis <= 2; ++axis) {
    const ScalarObs obs = mm_nhc(x, quat_to_dcm(x.q_nav_body), axis, Real(0.1));
    const ErrRow num = numeric_jacobian(x, [&](const NominalState& y) {
      return static_cast<double>(mm_nhc_predict(y, quat_to_dcm(y.q_nav_body), axis));
    });
    expect_row_near(obs.h, num, kTol);
    EXPECT_NEAR(static_cast<double>(obs.innovation),
                -static_cast<double>(mm_nhc_predict(x, quat_to_dcm(x.q_nav_body), axis)), 1e-6);
  }
}

TEST(MmNhc, RoadFrameVerticalJacobianMatchesNumeric) {
  const NominalState x = sample_state();
  const Real pitch = Real(0.012);
  const ScalarObs obs = mm_nhc(x, quat_to_dcm(x.q_nav_body), 2, Real(0.1), pitch);
  const ErrRow num = numeric_jacobian(x, [&](const NominalState& y) {
    return static_cast<double>(mm_nhc_predict(y, quat_to_dcm(y.q_nav_body), 2, pitch));
  });
  expect_row_near(obs.h, num, kTol);
  EXPECT_NEAR(static_cast<double>(obs.innovation),
              -static_cast<double>(mm_nhc_predict(x, quat_to_dcm(x.q_nav_body), 2, pitch)), 1e-6);
}

TEST(MmNhc, VerticalConstraintHoldsForABodyPitchedNoseDownByTheSuspensionOnALevelRoad) {
  // GIVEN a car at 8 m/s along a level road heading 30 deg, its body pitched
  // 10 mrad nose down (positive about body y) by braking
  NominalState x;
  const Real yaw = Real(0.5236);
  const Real pitch = Real(0.010);
  x.vel_nav_mps = Vec3(Real(8) * std::cos(yaw), Real(8) * std::sin(yaw), Real(0));
  const Quat nose_down(std::cos(pitch / 2), Real(0), std::sin(pitch / 2), Real(0));  // about body y
  x.q_nav_body = quat_normalised(quat_mul(quat_from_yaw(yaw), nose_down));
  const Mat3 c = quat_to_dcm(x.q_nav_body);
  // THEN the body-frame vertical velocity is v sin(theta) = 0.08 m/s, which the
  // body-frame constraint reads as a violation and the road-frame one does not
  EXPECT_NEAR(static_cast<double>(mm_nhc_predict(x, c, 2)), 0.08, 1e-3);
  EXPECT_NEAR(static_cast<double>(mm_nhc(x, c, 2, Real(0.1), pitch).innovation), 0.0, 1e-5);
  // AND the lateral constraint does not depend on the pitch
  EXPECT_NEAR(static_cast<double>(mm_nhc(x, c, 1, Real(0.1), pitch).innovation),
              static_cast<double>(mm_nhc(x, c, 1, Real(0.1)).innovation), 1e-7);
}

TEST(MmZupt, VelocityAndGyroBiasJacobiansMatchNumeric) {
  const NominalState x = sample_state();
  const Vec3 gyro_mean(Real(0.01), Real(0.02), Real(-0.01));
  for (int axis = 0; axis < 3; ++axis) {
    const ScalarObs z = mm_zupt(x, axis, Real(0.02));
    expect_row_near(z.h, numeric_jacobian(x, [&](const NominalState& y) {
                      return static_cast<double>(y.vel_nav_mps(axis));
                    }),
                    kTol);
    const ScalarObs w = mm_zaru(x, gyro_mean, axis, Real(0.002));
    expect_row_near(w.h, numeric_jacobian(x, [&](const NominalState& y) {
                      return static_cast<double>(y.bg_body_radps(axis));
                    }),
                    kTol);
    EXPECT_NEAR(static_cast<double>(w.innovation), static_cast<double>(gyro_mean(axis) - x.bg_body_radps(axis)),
                1e-6);
  }
}

TEST(MmHeight, JacobianMatchesNumeric) {
  const NominalState x = sample_state();
  const ScalarObs obs = mm_height(x, Real(0.1), Real(0.1));
  expect_row_near(obs.h, numeric_jacobian(x, [](const NominalState& y) { return static_cast<double>(y.pos_nav_m.z()); }),
                  kTol);
  EXPECT_NEAR(static_cast<double>(obs.innovation), 0.1 - 0.4, 1e-6);
}

TEST(MmPosition, JacobianMatchesNumericOnBothHorizontalAxes) {
  const NominalState x = sample_state();
  for (int axis = 0; axis < 2; ++axis) {
    const ScalarObs obs = mm_position(x, axis, Real(2.5), Real(0.04));
    expect_row_near(obs.h,
                    numeric_jacobian(x, [axis](const NominalState& y) { return static_cast<double>(y.pos_nav_m(axis)); }),
                    kTol);
    EXPECT_NEAR(static_cast<double>(obs.innovation), 2.5 - static_cast<double>(x.pos_nav_m(axis)), 1e-6);
    EXPECT_EQ(obs.r_var, Real(0.04));
  }
}

// GNSS antenna prediction of a late fix (dt < 0) on a turning vehicle with a
// 1.5 m mast: the innovation is measured minus predicted, so the Jacobian of
// the prediction is minus the numeric derivative of the innovation.
GnssPredictionInput gnss_input(const NominalState& x, Real dt) {
  GnssPredictionInput in;
  in.x = &x;
  in.c_nav_body = quat_to_dcm(x.q_nav_body);
  in.gyro_body_radps = Vec3(Real(0.3), Real(-0.2), Real(0.8));
  in.accel_nav_mps2 = Vec3(Real(1.5), Real(-0.7), Real(0.1));
  in.lever_body_m = Vec3(Real(0.8), Real(-0.3), Real(1.5));
  in.dt_s = dt;
  return in;
}

TEST(MmGnss, PositionJacobianWithLeverArmAndLatencyMatchesNumericOnEveryAxis) {
  const NominalState x = sample_state();
  const Real dt = Real(-0.12);
  for (int axis = 0; axis < 3; ++axis) {
    const ScalarObs obs = mm_gnss_position(gnss_input(x, dt), axis, Real(0), Real(1));
    const ErrRow num = numeric_jacobian(x, [&](const NominalState& y) {
      return -static_cast<double>(mm_gnss_position(gnss_input(y, dt), axis, Real(0), Real(1)).innovation);
    });
    expect_row_near(obs.h, num, kTol);
    EXPECT_EQ(obs.h(ErrIdx::kPos + axis), Real(1)) << "axis " << axis;
    EXPECT_EQ(obs.h(ErrIdx::kVel + axis), dt) << "the fix describes the state dt earlier";
    // Nothing of the range errors: GNSS does not see the UWB offsets.
    EXPECT_EQ(obs.h.tail<ErrIdx::kRange>().norm(), Real(0));
  }
}

TEST(MmGnss, VelocityJacobianWithLeverArmRotationMatchesNumericOnEveryAxis) {
  const NominalState x = sample_state();
  for (int axis = 0; axis < 3; ++axis) {
    const ScalarObs obs = mm_gnss_velocity(gnss_input(x, Real(-0.08)), axis, Real(0), Real(1));
    const ErrRow num = numeric_jacobian(x, [&](const NominalState& y) {
      return -static_cast<double>(mm_gnss_velocity(gnss_input(y, Real(-0.08)), axis, Real(0), Real(1)).innovation);
    });
    expect_row_near(obs.h, num, kTol);
    // The mast's rotation (w x l) ties the velocity to attitude and gyro bias.
    EXPECT_GT(obs.h.segment<3>(ErrIdx::kAtt).norm() + obs.h.segment<3>(ErrIdx::kBg).norm(), Real(0.1));
  }
}

TEST(MmGnss, PredictsTheAntennaNotTheBodyOriginAtTheFixTime) {
  NominalState x;
  x.pos_nav_m = Vec3(Real(10), Real(20), Real(0));
  x.vel_nav_mps = Vec3(Real(5), Real(0), Real(0));
  x.q_nav_body = quat_from_yaw(kPi / Real(2));  // body x points to nav y
  GnssPredictionInput in;
  in.x = &x;
  in.c_nav_body = quat_to_dcm(x.q_nav_body);
  in.lever_body_m = Vec3(Real(1), Real(0), Real(1.5));
  in.dt_s = Real(-0.1);  // 100 ms latency: 0.5 m back along the track
  const Real tol = Real(1e-5);
  EXPECT_NEAR(static_cast<double>(mm_gnss_position(in, 0, Real(9.5), Real(1)).innovation), 0.0, tol);
  EXPECT_NEAR(static_cast<double>(mm_gnss_position(in, 1, Real(21), Real(1)).innovation), 0.0, tol);
  EXPECT_NEAR(static_cast<double>(mm_gnss_position(in, 2, Real(1.5), Real(1)).innovation), 0.0, tol);
  // Axis out of range is clamped, never an out-of-bounds read.
  EXPECT_TRUE(std::isfinite(mm_gnss_position(in, 7, Real(0), Real(1)).innovation));
}

}  // namespace
}  // namespace uwbnav
