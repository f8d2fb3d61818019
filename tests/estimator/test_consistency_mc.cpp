// Monte-Carlo consistency of each model of the error-state EKF (issue 13 item 4):
// truths are drawn from the filter's own prior and driven by the noise the
// model claims; the normalised estimation error squared (NEES) averaged over
// the runs must then be chi-square with the state's dimension. A model whose
// Jacobian, process noise or update is wrong shows as a mean NEES outside the
// two-sided 99.9 % band of that distribution.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "estimator/bias_window.hpp"
#include "estimator/ekf_core.hpp"
#include "error_injection.hpp"
#include "estimator/mm_height.hpp"
#include "estimator/mm_nhc.hpp"
#include "estimator/mm_range.hpp"
#include "estimator/mm_zupt.hpp"

namespace uwbnav {
namespace {

using Rng = std::mt19937_64;

using test::inject;

// truth (-) estimate as an error-state vector (attitude: small angle of C_true C_est^T).
Eigen::VectorXd error_of(const NominalState& truth, const NominalState& est) {
  Eigen::VectorXd e(kN);
  const Mat3 dc = quat_to_dcm(truth.q_nav_body) * quat_to_dcm(est.q_nav_body).transpose();
  const Vec3 dtheta(Real(0.5) * (dc(2, 1) - dc(1, 2)), Real(0.5) * (dc(0, 2) - dc(2, 0)),
                    Real(0.5) * (dc(1, 0) - dc(0, 1)));
  for (int i = 0; i < 3; ++i) {
    e(ErrIdx::kPos + i) = static_cast<double>(truth.pos_nav_m(i) - est.pos_nav_m(i));
    e(ErrIdx::kVel + i) = static_cast<double>(truth.vel_nav_mps(i) - est.vel_nav_mps(i));
    e(ErrIdx::kAtt + i) = static_cast<double>(dtheta(i));
    e(ErrIdx::kBa + i) = static_cast<double>(truth.ba_body_mps2(i) - est.ba_body_mps2(i));
    e(ErrIdx::kBg + i) = static_cast<double>(truth.bg_body_radps(i) - est.bg_body_radps(i));
  }
  for (int i = 0; i < ErrIdx::kRange; ++i) e(ErrIdx::kCore + i) = static_cast<double>(truth.range_err(i) - est.range_err(i));
  return e;
}

// NEES of the states `idx` (error e, covariance p).
double nees(const Eigen::VectorXd& e, const ErrCov& p, const std::vector<int>& idx) {
  const int n = static_cast<int>(idx.size());
  Eigen::MatrixXd s(n, n);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) {
    v(i) = e(idx[static_cast<size_t>(i)]);
    for (int j = 0; j < n; ++j) s(i, j) = static_cast<double>(p(idx[static_cast<size_t>(i)], idx[static_cast<size_t>(j)]));
  }
  return v.dot(s.ldlt().solve(v));
}

// Mean NEES over `runs` runs of an n-dimensional state is chi2(runs n) / runs:
// mean n, standard deviation sqrt(2 n / runs). 3.3 sigma ~ two-sided 99.9 %.
void expect_chi2_mean(double mean_nees, int n, int runs, const char* what) {
  const double sd = std::sqrt(2.0 * n / runs);
  std::printf("%s: mean NEES %.3f for %d states over %d runs (band %.3f..%.3f)\n", what, mean_nees, n, runs,
              n - 3.3 * sd, n + 3.3 * sd);
  EXPECT_GT(mean_nees, n - 3.3 * sd) << what << ": covariance pessimistic";
  EXPECT_LT(mean_nees, n + 3.3 * sd) << what << ": covariance optimistic";
}

// A draw from N(0, diag(sigma^2)).
ErrVec draw(Rng& rng, const ErrVec& sigma) {
  std::normal_distribution<double> n01(0.0, 1.0);
  ErrVec d;
  for (int i = 0; i < kN; ++i) d(i) = static_cast<Real>(n01(rng)) * sigma(i);
  return d;
}

std::vector<int> indices(int first, int count) {
  std::vector<int> v;
  for (int i = 0; i < count; ++i) v.push_back(first + i);
  return v;
}

// Four anchors around a tag 1.7 m high; anchor k reads anchor-offset slot k.
const Vec3 kAnchors[4] = {Vec3(0, 0, Real(2.5)), Vec3(30, 0, Real(1.5)), Vec3(30, 20, Real(3)), Vec3(0, 20, Real(1))};

ErrVec range_prior_sigma() {
  ErrVec s = ErrVec::Constant(Real(1e-6));
  s.segment<3>(ErrIdx::kPos) = Vec3(Real(0.3), Real(0.3), Real(0.2));
  s(ErrIdx::kScale) = Real(0.003);
  s(ErrIdx::kTagBias) = Real(0.1);
  for (int k = 0; k < 4; ++k) s(ErrIdx::kAnchorBias + k) = Real(0.1);
  return s;
}

// One run of range updates at 8 tag positions (the tag is carried from one to
// the next exactly: the filter's position moves by the same known step), so
// that offsets, scale and position are partly separable.
void run_range_updates(Rng& rng, bool consider, ErrCov* p_out, Eigen::VectorXd* e_out) {
  constexpr Real kSigmaRange_m = Real(0.05);
  const ErrVec sigma0 = range_prior_sigma();
  NominalState est;
  est.pos_nav_m = Vec3(Real(8), Real(6), Real(1.7));
  const NominalState truth0 = inject(est, draw(rng, sigma0));
  NominalState truth = truth0;
  EkfCore ekf;
  ekf.init(est, sigma0);
  std::normal_distribution<double> noise(0.0, static_cast<double>(kSigmaRange_m));
  const Mat3 c = Mat3::Identity();
  Vec3 prev_step = Vec3::Zero();
  for (int stop = 0; stop < 8; ++stop) {
    // Truth and estimate move by the same known step.
    const Vec3 step(Real(2.5) * static_cast<Real>(stop % 4), Real(2) * static_cast<Real>(stop / 4), Real(0));
    truth.pos_nav_m = truth0.pos_nav_m + step;
    ekf.mutable_state().pos_nav_m += step - prev_step;
    prev_step = step;
    for (int k = 0; k < 4; ++k) {
      RangeErrorSlots slots;
      slots.tag_index = 0;
      slots.anchor_slot = k;
      const RangePrediction truth_pred = mm_range_predict(truth, c, Vec3::Zero(), Vec3::Zero(), kAnchors[k], 0, slots);
      const Real measured = truth_pred.range_m + static_cast<Real>(noise(rng));
      const RangePrediction pred = mm_range_predict(ekf.state(), c, Vec3::Zero(), Vec3::Zero(), kAnchors[k], 0, slots);
      ASSERT_TRUE(pred.valid);
      (void)ekf.prepare(pred.h);
      ASSERT_TRUE(ekf.update_prepared(measured - pred.range_m, kSigmaRange_m * kSigmaRange_m, consider).applied);
    }
  }
  *p_out = ekf.cov();
  *e_out = error_of(truth, ekf.state());
}

TEST(ConsistencyMc, RangeUpdatesWithScaleAndOffsetStatesAreChiSquareConsistent) {
  // GIVEN truths drawn from the prior (position 0.3 m, scale 0.3 %, tag and
  // anchor offsets 0.1 m) and ranges made with the model plus 5 cm noise
  Rng rng(13);
  constexpr int kRuns = 400;
  double sum = 0.0;
  std::vector<int> idx = indices(ErrIdx::kPos, 3);
  idx.push_back(ErrIdx::kScale);
  idx.push_back(ErrIdx::kTagBias);
  for (int k = 0; k < 4; ++k) idx.push_back(ErrIdx::kAnchorBias + k);
  for (int r = 0; r < kRuns; ++r) {
    ErrCov p;
    Eigen::VectorXd e;
    // WHEN the filter fuses them, learning every range error
    run_range_updates(rng, false, &p, &e);
    if (HasFatalFailure()) return;
    sum += nees(e, p, idx);
  }
  // THEN position, scale and offsets are chi-square consistent
  expect_chi2_mean(sum / kRuns, static_cast<int>(idx.size()), kRuns, "range updates, errors estimated");
}

TEST(ConsistencyMc, SchmidtConsiderRangeUpdatesKeepThePositionConsistent) {
  // GIVEN the same truths, the range errors treated as consider states
  Rng rng(14);
  constexpr int kRuns = 400;
  double sum_pos = 0.0;
  double sum_consider = 0.0;
  const std::vector<int> pos = indices(ErrIdx::kPos, 3);
  std::vector<int> cons;
  cons.push_back(ErrIdx::kScale);
  cons.push_back(ErrIdx::kTagBias);
  for (int k = 0; k < 4; ++k) cons.push_back(ErrIdx::kAnchorBias + k);
  for (int r = 0; r < kRuns; ++r) {
    ErrCov p;
    Eigen::VectorXd e;
    // WHEN the filter fuses them without estimating the range errors
    run_range_updates(rng, true, &p, &e);
    if (HasFatalFailure()) return;
    sum_pos += nees(e, p, pos);
    sum_consider += nees(e, p, cons);
  }
  // THEN the estimated position is consistent, and the consider states keep
  // their prior (their error is the truth's deviation from zero)
  expect_chi2_mean(sum_pos / kRuns, 3, kRuns, "Schmidt consider, position");
  expect_chi2_mean(sum_consider / kRuns, static_cast<int>(cons.size()), kRuns, "Schmidt consider, range errors");
}

TEST(ConsistencyMc, ConstantVelocityPredictionCoversWhiteAccelerationTruths) {
  // GIVEN truths that accelerate with white noise of the claimed density
  // (integrated in 1 ms steps) from a prior of 0.2 m / 0.5 m/s
  Rng rng(15);
  constexpr int kRuns = 600;
  constexpr Real kPsd = Real(1.5);      // [m/s^2/sqrt(Hz)]
  constexpr Real kHorizon_s = Real(2);  // one prediction over 2 s
  constexpr int kSub = 2000;
  ErrVec sigma0 = ErrVec::Constant(Real(1e-6));
  sigma0.segment<3>(ErrIdx::kPos).setConstant(Real(0.2));
  sigma0.segment<3>(ErrIdx::kVel).setConstant(Real(0.5));
  NominalState est;
  est.pos_nav_m = Vec3(Real(3), Real(-4), Real(1));
  est.vel_nav_mps = Vec3(Real(4), Real(1), Real(0));
  std::normal_distribution<double> n01(0.0, 1.0);
  double sum = 0.0;
  const double h = static_cast<double>(kHorizon_s) / kSub;
  for (int r = 0; r < kRuns; ++r) {
    const NominalState t0 = inject(est, draw(rng, sigma0));
    Eigen::Vector3d p, v;
    for (int i = 0; i < 3; ++i) {
      p(i) = static_cast<double>(t0.pos_nav_m(i));
      v(i) = static_cast<double>(t0.vel_nav_mps(i));
    }
    for (int k = 0; k < kSub; ++k) {
      Eigen::Vector3d a;
      for (int i = 0; i < 3; ++i) a(i) = n01(rng) * static_cast<double>(kPsd) / std::sqrt(h);
      p += v * h + 0.5 * a * h * h;
      v += a * h;
    }
    NominalState truth = t0;
    truth.pos_nav_m = p.cast<Real>();
    truth.vel_nav_mps = v.cast<Real>();
    // WHEN the filter predicts once over the whole horizon
    EkfCore ekf;
    ekf.init(est, sigma0);
    ekf.predict_cv(kHorizon_s, kPsd, Real(0), Real(0));
    sum += nees(error_of(truth, ekf.state()), ekf.cov(), indices(ErrIdx::kPos, 6));
  }
  // THEN its position and velocity covariance matches the spread
  expect_chi2_mean(sum / kRuns, 6, kRuns, "constant-velocity prediction");
}

TEST(ConsistencyMc, MeanRevertingVelocityPredictionCoversOrnsteinUhlenbeckTruths) {
  // GIVEN truths whose velocity mean-reverts (time constant 2 s) under white
  // acceleration of the claimed density, integrated in 1 ms steps over a
  // 6 s gap (3 time constants: the closed-form branch of cv_step), and over a
  // 20 ms step (its series branch)
  for (const Real horizon_s : {Real(6), Real(0.02)}) {
    Rng rng(17);
    constexpr int kRuns = 600;
    constexpr Real kPsd = Real(1.5);  // [m/s^2/sqrt(Hz)]
    constexpr Real kTau_s = Real(2);
    const int sub = static_cast<int>(std::lround(static_cast<double>(horizon_s) * 1000.0));
    ErrVec sigma0 = ErrVec::Constant(Real(1e-6));
    sigma0.segment<3>(ErrIdx::kPos).setConstant(Real(0.2));
    sigma0.segment<3>(ErrIdx::kVel).setConstant(Real(0.5));
    NominalState est;
    est.pos_nav_m = Vec3(Real(3), Real(-4), Real(1));
    est.vel_nav_mps = Vec3(Real(4), Real(1), Real(0));
    std::normal_distribution<double> n01(0.0, 1.0);
    double sum = 0.0;
    const double h = static_cast<double>(horizon_s) / sub;
    const double tau = static_cast<double>(kTau_s);
    for (int r = 0; r < kRuns; ++r) {
      const NominalState t0 = inject(est, draw(rng, sigma0));
      Eigen::Vector3d p, v;
      for (int i = 0; i < 3; ++i) {
        p(i) = static_cast<double>(t0.pos_nav_m(i));
        v(i) = static_cast<double>(t0.vel_nav_mps(i));
      }
      for (int k = 0; k < sub; ++k) {
        Eigen::Vector3d a;
        for (int i = 0; i < 3; ++i) a(i) = n01(rng) * static_cast<double>(kPsd) / std::sqrt(h) - v(i) / tau;
        p += v * h + 0.5 * a * h * h;
        v += a * h;
      }
      NominalState truth = t0;
      truth.pos_nav_m = p.cast<Real>();
      truth.vel_nav_mps = v.cast<Real>();
      // WHEN the filter predicts once over the whole horizon
      EkfCore ekf;
      ekf.init(est, sigma0);
      ekf.predict_cv(horizon_s, kPsd, Real(0), kTau_s);
      sum += nees(error_of(truth, ekf.state()), ekf.cov(), indices(ErrIdx::kPos, 6));
    }
    // THEN its position and velocity covariance matches the spread
    expect_chi2_mean(sum / kRuns, 6, kRuns, "mean-reverting velocity prediction");
  }
}

TEST(ConsistencyMc, CvStepSeriesAndClosedFormAgreeAtTheSwitch) {
  // GIVEN one step just below and just above the switch x = dt/tau = 0.2
  // WHEN both branches are evaluated
  const CvStep lo = cv_step(Real(0.1999999), Real(1.3), Real(1));
  const CvStep hi = cv_step(Real(0.2000001), Real(1.3), Real(1));
  // THEN the transition and the process noise are continuous there (a wrong
  // series term, or a switch where the closed form still cancels, would show
  // as a jump of more than float round-off)
  EXPECT_NEAR(lo.f_vv, hi.f_vv, 1e-6F);
  EXPECT_NEAR(lo.f_pv / hi.f_pv, 1.0F, 1e-4F);
  EXPECT_NEAR(lo.q_vv / hi.q_vv, 1.0F, 1e-4F);
  EXPECT_NEAR(lo.q_pv / hi.q_pv, 1.0F, 1e-4F);
  EXPECT_NEAR(lo.q_pp / hi.q_pp, 1.0F, 3e-4F);
}

TEST(ConsistencyMc, CvStepSeriesMatchesTheClosedFormInDoubleWhereFloatWouldCancel) {
  // GIVEN small steps x = dt/tau from 1e-3 to 0.19 (the series branch)
  for (const double x : {1e-3, 0.02, 0.1, 0.19}) {
    // WHEN cv_step evaluates them in the estimator's precision
    const CvStep st = cv_step(static_cast<Real>(x), Real(1), Real(1));
    // THEN it matches the closed form evaluated in double
    const double phi = std::exp(-x);
    const double q_pp = 0.5 * (2.0 * x - 3.0 + 4.0 * phi - phi * phi);
    const double q_pv = 0.5 * (1.0 - phi) * (1.0 - phi);
    const double q_vv = 0.5 * (1.0 - phi * phi);
    EXPECT_NEAR(static_cast<double>(st.f_vv), phi, 1e-6) << x;
    EXPECT_NEAR(static_cast<double>(st.f_pv) / (1.0 - phi), 1.0, 1e-5) << x;
    EXPECT_NEAR(static_cast<double>(st.q_vv) / q_vv, 1.0, 1e-4) << x;
    EXPECT_NEAR(static_cast<double>(st.q_pv) / q_pv, 1.0, 1e-4) << x;
    EXPECT_NEAR(static_cast<double>(st.q_pp) / q_pp, 1.0, 1e-4) << x;
  }
}

TEST(ConsistencyMc, ImuPredictionCoversNoisyAndBiasedImuTruths) {
  // GIVEN truths drawn from the prior (including accelerometer and gyro
  // biases) that turn and accelerate, and the IMU they would measure: true
  // rate and force plus bias plus white noise of the claimed densities
  Rng rng(16);
  constexpr int kRuns = 300;
  constexpr Real kDt_s = Real(0.01);
  constexpr int kSteps = 500;  // 5 s
  constexpr Real kG = Real(9.80665);
  ImuNoise nz;
  nz.accel_noise = Real(0.02);
  nz.gyro_noise = Real(0.002);
  nz.accel_bias_rw = Real(0.002);
  nz.gyro_bias_rw = Real(1e-4);
  ErrVec sigma0 = ErrVec::Constant(Real(1e-6));
  sigma0.segment<3>(ErrIdx::kPos).setConstant(Real(0.1));
  sigma0.segment<3>(ErrIdx::kVel).setConstant(Real(0.1));
  sigma0.segment<3>(ErrIdx::kAtt) = Vec3(Real(0.01), Real(0.01), Real(0.03));
  sigma0.segment<3>(ErrIdx::kBa).setConstant(Real(0.05));
  sigma0.segment<3>(ErrIdx::kBg).setConstant(Real(0.002));
  NominalState est;
  est.pos_nav_m = Vec3(Real(5), Real(2), Real(1));
  est.vel_nav_mps = Vec3(Real(3), Real(0), Real(0));
  est.q_nav_body = quat_from_yaw(Real(0.3));
  const Vec3 force_body(Real(0.8), Real(0.3), kG);  // accelerating and turning
  const Vec3 rate_body(Real(0), Real(0), Real(0.15));
  std::normal_distribution<double> n01(0.0, 1.0);
  auto white = [&](Real density) -> Vec3 {
    return Vec3(static_cast<Real>(n01(rng)), static_cast<Real>(n01(rng)), static_cast<Real>(n01(rng))) *
           (density / std::sqrt(kDt_s));
  };
  double sum = 0.0;
  for (int r = 0; r < kRuns; ++r) {
    NominalState t = inject(est, draw(rng, sigma0));
    EkfCore truth;
    truth.init(t, ErrVec::Constant(Real(1e-6)));
    EkfCore ekf;
    ekf.init(est, sigma0);
    for (int k = 0; k < kSteps; ++k) {
      // The truth moves with the true force and rate: its own mechanisation fed
      // with them plus its biases (which it subtracts again).
      const NominalState& ts = truth.state();
      const Vec3 f_meas = force_body + ts.ba_body_mps2;
      const Vec3 w_meas = rate_body + ts.bg_body_radps;
      truth.predict_imu(f_meas, w_meas, kDt_s, kG, ImuNoise{});
      ekf.predict_imu(f_meas + white(nz.accel_noise), w_meas + white(nz.gyro_noise), kDt_s, kG, nz);
      // Bias random walks of the truth.
      NominalState tb = truth.state();
      tb.ba_body_mps2 += white(nz.accel_bias_rw) * kDt_s;
      tb.bg_body_radps += white(nz.gyro_bias_rw) * kDt_s;
      truth.mutable_state() = tb;
    }
    sum += nees(error_of(truth.state(), ekf.state()), ekf.cov(), indices(0, ErrIdx::kCore));
  }
  // WHEN the filter propagates 5 s on the noisy IMU THEN its 15 core states are consistent
  expect_chi2_mean(sum / kRuns, ErrIdx::kCore, kRuns, "IMU prediction");
}

TEST(ConsistencyMc, ConstraintUpdatesKeepTheCoreConsistent) {
  // GIVEN truths from the prior of a moving ground vehicle and the constraint
  // pseudo-measurements it satisfies up to their claimed noise: zero lateral and
  // vertical body velocity (NHC) and a known height
  Rng rng(17);
  constexpr int kRuns = 400;
  ErrVec sigma0 = ErrVec::Constant(Real(1e-6));
  sigma0.segment<3>(ErrIdx::kPos).setConstant(Real(0.3));
  sigma0.segment<3>(ErrIdx::kVel).setConstant(Real(0.3));
  sigma0.segment<3>(ErrIdx::kAtt) = Vec3(Real(0.01), Real(0.01), Real(0.05));
  NominalState est;
  est.pos_nav_m = Vec3(Real(5), Real(2), Real(0));
  est.vel_nav_mps = Vec3(Real(6), Real(2), Real(0));
  est.q_nav_body = quat_from_yaw(std::atan2(Real(2), Real(6)));
  constexpr Real kNhcSigma = Real(0.05);
  constexpr Real kHeightSigma = Real(0.05);
  std::normal_distribution<double> n01(0.0, 1.0);
  double sum = 0.0;
  for (int r = 0; r < kRuns; ++r) {
    const NominalState t = inject(est, draw(rng, sigma0));
    const Mat3 ct = quat_to_dcm(t.q_nav_body);
    const Vec3 v_body_true = ct.transpose() * t.vel_nav_mps;
    EkfCore ekf;
    ekf.init(est, sigma0);
    // Each pseudo-measurement as its model reads it at the truth, plus noise:
    // innovation = (truth value + noise) - model value at the estimate.
    for (int axis = 1; axis <= 2; ++axis) {
      ScalarObs obs = mm_nhc(ekf.state(), ekf.dcm(), axis, kNhcSigma);
      const Real model_at_est = -obs.innovation;  // mm_nhc: innovation = 0 - v_body(axis)
      obs.innovation = v_body_true(axis) + static_cast<Real>(n01(rng)) * kNhcSigma - model_at_est;
      ASSERT_TRUE(ekf.update(obs).applied);
    }
    ScalarObs hobs = mm_height(ekf.state(), Real(0), kHeightSigma);
    const Real h_model = -hobs.innovation;  // mm_height: innovation = ref - z
    hobs.innovation = t.pos_nav_m.z() + static_cast<Real>(n01(rng)) * kHeightSigma - h_model;
    ASSERT_TRUE(ekf.update(hobs).applied);
    sum += nees(error_of(t, ekf.state()), ekf.cov(), indices(0, 9));
  }
  // THEN position, velocity and attitude stay chi-square consistent
  expect_chi2_mean(sum / kRuns, 9, kRuns, "NHC + height updates");
}

// A walk measured directly, with white noise, for the bias-instability
// statistics: the gyro bias (BiasWindow::ratio: one window's summed bias
// corrections, squared, over the variance the model gave them) or the tilt
// (EkfCore::tilt_tally(): one window's summed tilt corrections, squared, over
// the variance the updates removed). Each walks with density
// sqrt(q_true_scale) * q_model while the filter models q_model; the result is
// the statistic's mean over the axes and windows.
struct WalkCase {
  int first_state;    // ErrIdx of the walking states
  int axes;           // how many
  double q_model;     // modelled walk density [unit/sqrt(s)]
  double meas_sigma;  // direct measurement noise [unit]
  bool tilt;          // read the tilt tally (else the gyro-bias window ratio)
};
constexpr WalkCase kGyroBiasWalk{ErrIdx::kBg, 3, 1e-5, 2e-4, false};  // imu.gyro_bias_rw's default [rad/s^2/sqrt(Hz)]
constexpr WalkCase kTiltWalk{ErrIdx::kAtt, 2, 1e-3, 2e-3, true};      // [rad/sqrt(s)], [rad]

double correction_ratio(const WalkCase& c, double q_true_scale, uint64_t seed) {
  constexpr double kDt = 0.01;          // [s] propagation step
  constexpr int kStepsPerMeas = 10;     // a measurement of each axis at 10 Hz
  constexpr int kStepsPerWindow = 500;  // 5 s, the Navigator's window
  constexpr int kWarmupWindows = 20;
  constexpr int kWindows = 300;
  Rng rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Constant(Real(1e-3)));
  BiasWindow win;
  double truth[3] = {0, 0, 0};
  const double walk = c.q_model * std::sqrt(q_true_scale * kDt);
  double ratio_sum = 0.0;
  int ratio_n = 0;
  for (int w = 0; w < kWarmupWindows + kWindows; ++w) {
    win.open(ekf.state(), ekf.cov());
    ekf.clear_tilt_tally();
    for (int k = 0; k < kStepsPerWindow; ++k) {
      for (int i = 0; i < c.axes; ++i) {
        truth[i] += walk * n01(rng);
        ekf.add_variance(c.first_state + i, static_cast<Real>(c.q_model * c.q_model * kDt));
      }
      win.predicted(static_cast<Real>(kDt));
      if (k % kStepsPerMeas != 0) continue;
      for (int i = 0; i < c.axes; ++i) {
        // Small angles: the nav-frame tilt of the nominal attitude is 2 q_xyz / q_w.
        const Quat& q = ekf.state().q_nav_body;
        const double estimate = c.tilt ? 2.0 * static_cast<double>(q(1 + i)) / static_cast<double>(q(0))
                                       : static_cast<double>(ekf.state().bg_body_radps(i));
        ScalarObs obs;
        obs.h(c.first_state + i) = Real(1);
        obs.innovation = static_cast<Real>(truth[i] + c.meas_sigma * n01(rng) - estimate);
        obs.r_var = static_cast<Real>(c.meas_sigma * c.meas_sigma);
        EXPECT_TRUE(ekf.update(obs).applied);
      }
    }
    Real r = Real(0);
    if (c.tilt) {
      const TiltTally& t = ekf.tilt_tally();
      for (int i = 0; i < c.axes; ++i) {
        EXPECT_GT(t.removed_var_rad2(i), Real(0));
        r += t.correction_sum_rad(i) * t.correction_sum_rad(i) / t.removed_var_rad2(i) / static_cast<Real>(c.axes);
      }
    } else {
      r = win.ratio(BiasWindow::kGyro, ekf.state(), ekf.cov(), static_cast<Real>(c.q_model), Real(1e6), TiltTally{});
      EXPECT_GE(r, Real(0));  // every axis was updated
    }
    if (w < kWarmupWindows) continue;
    ratio_sum += static_cast<double>(r);
    ++ratio_n;
  }
  return ratio_sum / ratio_n;
}

TEST(ConsistencyMc, BiasCorrectionSumsMatchTheirModelVarianceUnlessTheBiasWalksFasterThanModelled) {
  // GIVEN a gyro bias that walks exactly as the filter models it
  // WHEN its direct measurements are fused for 300 windows of 5 s
  // THEN each window's summed correction, squared, averages its model variance
  // (chi-square with 1 dof per axis and window: mean 1, sd sqrt(2/900) = 0.047)
  const double consistent = correction_ratio(kGyroBiasWalk, 1.0, 31);
  // AND a bias that walks with 16 times the modelled variance (a consumer gyro
  // under the MEMS default) leaves corrections that add up far beyond it
  const double too_fast = correction_ratio(kGyroBiasWalk, 16.0, 32);
  std::printf("bias correction ratio: modelled walk %.3f, 16x walk %.3f\n", consistent, too_fast);
  EXPECT_NEAR(consistent, 1.0, 0.16);
  EXPECT_GT(too_fast, 3.0);
}

TEST(ConsistencyMc, TiltCorrectionSumsMatchTheVarianceTheyRemovedUnlessTheTiltWalksFasterThanModelled) {
  // GIVEN a tilt that walks exactly as the filter models it
  // WHEN its direct measurements are fused for 300 windows of 5 s
  // THEN each window's summed tilt correction (EkfCore's tally), squared,
  // averages the variance the updates removed (chi-square with 1 dof per axis
  // and window: mean 1, sd 0.058 over 600 independent terms; seeds 41, 43, 44
  // gave 0.90, 1.17, 0.95, a wider spread: the tolerance is 0.3)
  const double consistent = correction_ratio(kTiltWalk, 1.0, 41);
  // AND a tilt that walks with 16 times the modelled variance (a gyro bias
  // walking faster than modelled, explained as tilt) leaves corrections that
  // add up far beyond it
  const double too_fast = correction_ratio(kTiltWalk, 16.0, 42);
  std::printf("tilt correction ratio: modelled walk %.3f, 16x walk %.3f\n", consistent, too_fast);
  EXPECT_NEAR(consistent, 1.0, 0.3);
  EXPECT_GT(too_fast, 3.0);
}

TEST(ConsistencyMc, TheGyroRatioPoolsTheTiltAxesAndTheAccelerometerRatioIgnoresThem) {
  // GIVEN a window in which no update touched a bias state, and a tilt tally
  // whose summed corrections are 3 and 1 of their model sigmas (ratios 9, 1)
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Constant(Real(0.05)));
  BiasWindow win;
  win.open(ekf.state(), ekf.cov());
  win.predicted(Real(5));
  TiltTally tilt;
  tilt.correction_sum_rad = Vec2(Real(3e-3), Real(-2e-3));
  tilt.removed_var_rad2 = Vec2(Real(1e-6), Real(4e-6));
  // WHEN the window's ratios are read with that tally
  const Real gyro = win.ratio(BiasWindow::kGyro, ekf.state(), ekf.cov(), Real(1e-5), Real(1e6), tilt);
  const Real accel = win.ratio(BiasWindow::kAccel, ekf.state(), ekf.cov(), Real(1e-4), Real(1e6), tilt);
  // THEN the gyro's ratio is the tilt axes' mean (5: the untouched bias axes
  // carry no evidence), and the accelerometer has no evidence at all (-1)
  EXPECT_NEAR(static_cast<double>(gyro), 5.0, 1e-3);
  EXPECT_LT(static_cast<double>(accel), 0.0);
  // AND once the gyro bias axes carry evidence too, the mean is over all five
  for (int i = 0; i < 3; ++i) {
    ScalarObs obs;
    obs.h(ErrIdx::kBg + i) = Real(1);
    obs.innovation = Real(0);
    obs.r_var = Real(0.05) * Real(0.05);
    ASSERT_TRUE(ekf.update(obs).applied);
  }
  const Real pooled = win.ratio(BiasWindow::kGyro, ekf.state(), ekf.cov(), Real(1e-5), Real(1e6), tilt);
  EXPECT_NEAR(static_cast<double>(pooled), 10.0 / 5.0, 1e-3);  // (0 + 0 + 0 + 9 + 1) / 5
}

TEST(ConsistencyMc, ABiasProjectionThatIsNoCorrectionStaysOutOfTheBiasInstabilityRatio) {
  // GIVEN a window over accelerometer-bias corrections of direct measurements
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Constant(Real(0.05)));
  BiasWindow win;
  win.open(ekf.state(), ekf.cov());
  for (int k = 0; k < 50; ++k) {
    win.predicted(Real(0.1));
    for (int i = 0; i < 3; ++i) {
      ScalarObs obs;
      obs.h(ErrIdx::kBa + i) = Real(1);
      // a bias of 0.02 m/s^2 per axis (0.4 sigma of the prior), measured with noise
      obs.innovation = Real(0.02) + Real(0.002) * static_cast<Real>((k + i) % 3 - 1) - ekf.state().ba_body_mps2(i);
      obs.r_var = Real(1e-4);
      ASSERT_TRUE(ekf.update(obs).applied);
    }
  }
  const Real before = win.ratio(BiasWindow::kAccel, ekf.state(), ekf.cov(), Real(1e-4), Real(1e6), TiltTally{});
  // WHEN the nominal bias is moved by 0.05 m/s^2 along z outside any update
  // (the vertical balance's projection) and the window is told
  const Vec3 shift(0, 0, Real(0.05));
  NominalState moved = ekf.state();
  moved.ba_body_mps2 += shift;
  BiasWindow told = win;
  told.shifted(BiasWindow::kAccel, shift);
  // THEN its ratio is the one without the move; a window not told reads it
  // as a bias that walked several times farther than modelled
  const Real after = told.ratio(BiasWindow::kAccel, moved, ekf.cov(), Real(1e-4), Real(1e6), TiltTally{});
  const Real untold = win.ratio(BiasWindow::kAccel, moved, ekf.cov(), Real(1e-4), Real(1e6), TiltTally{});
  std::printf("accel bias ratio: %.3f, after a told shift %.3f, untold %.1f\n", static_cast<double>(before),
              static_cast<double>(after), static_cast<double>(untold));
  EXPECT_NEAR(static_cast<double>(after), static_cast<double>(before), 1e-3 * static_cast<double>(before) + 1e-6);
  EXPECT_GT(static_cast<double>(before), 0.05);
  EXPECT_GT(static_cast<double>(untold), 3.0 * static_cast<double>(before));
}

}  // namespace
}  // namespace uwbnav
