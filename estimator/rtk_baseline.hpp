// Carrier-phase relative positioning between two vehicles (issue 16 item 3,
// second building block): a fixed-size Kalman filter for the baseline b_nav_m
// from vehicle A's GNSS antenna to vehicle B's antenna plus single-frequency
// ambiguities, fed with pseudorange and carrier-phase double differences
// (DD) and optionally the inter-vehicle UWB range, followed by LAMBDA integer
// ambiguity resolution with the ratio test (estimator/lambda.hpp). Double
// precision, static memory, no exceptions, no I/O. docs/lambda.md "Relative
// positioning with double differences (rtk_baseline)".
//
// Seed paper 002: Xu A., Cao N., Sui X. et al., "Cooperative vehicle
// positioning method based on BDS/UWB", Science of Surveying and Mapping
// 45(6), 2020. Equation numbers below are the paper's: (3)/(4) between-receiver
// single differences, (5)/(6) double differences, (9) UWB baseline-length
// constraint, (11)/(12) linearisation, (13) observation model, (14) state
// model, (15)-(19) Kalman recursion, LAMBDA with RATIO > 3.
//
// Conventions (tested in tests/estimator/test_rtk_baseline.cpp):
//  - nav frame ENU-like, z up (docs/ekf.md). e_j: unit line-of-sight vector in
//    the nav frame from the receiver toward satellite j (shared by both
//    receivers: the baseline is short, 5-20 m).
//  - Inputs are single differences between receivers, B minus A:
//      code_sd_m   = P_B - P_A          = -e_j.b + c dt_AB + e        (paper (3))
//      carrier_sd_cyc = phi_B - phi_A, lambda phi_sd = -e_j.b + c dt_AB + lambda N_sd,j + e   (paper (4))
//    (x_B = x_A + b, so the range to j shrinks by e_j.b.) Satellite clock,
//    ionosphere and troposphere cancel or are neglected on a short baseline
//    (paper, after (4)).
//  - States: b_nav_m (3) and one single-difference ambiguity N_sd [cycles] per
//    tracked satellite slot. Double differences against the reference r are
//    formed in the measurement model, so the receiver clock difference c dt_AB
//    cancels (paper (5), (6)):
//      P_dd   = P_sd,j - P_sd,r             = -(e_j - e_r).b + e
//      lambda phi_dd                        = -(e_j - e_r).b + lambda (N_sd,j - N_sd,r) + e
//    A reference change therefore needs no re-mapping: the next epoch's DD
//    simply use the new reference (the DD ambiguities handed to LAMBDA are
//    D N_sd for the current reference). The common mode of N_sd is carried by
//    the initial prior only (N_sd is initialised from code-minus-carrier,
//    lambda phi_sd - P_sd = lambda N_sd + noise: the clock cancels there too).
//  - DD noise: per-receiver undifferenced sigma sigma_0 / sin(elevation),
//    SD variance 2 sigma^2, DD covariance D Sigma_SD D^T (not diagonal).
//  - UWB range between the two tags (paper (9)): h = |b| (antenna-to-tag lever
//    arms assumed known and zero in this block), Jacobian b^T/|b|; a scalar
//    iterated EKF update after the DD update, by default for the epoch's
//    solution only (RtkParams::uwb_accumulate).
//  - Robustness (not in seed 002): carrier fault exclusion and residual-based
//    R inflation per block before the update, at least min_fix_sats for a fix
//    (RtkParams).
//  - No fix-and-hold: the integer fix is reported (b_fix and its covariance)
//    but never fed back into the float filter.
#pragma once

#include "estimator/lambda.hpp"

#if UWBNAV_LAMBDA

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cstdint>

#include "estimator/status.hpp"

namespace uwbnav {

// Satellites per epoch: the reference plus up to kLambdaMaxAmb others.
constexpr int kRtkMaxSats = kLambdaMaxAmb + 1;
// Fewest common satellites for a DD update: 4 (3 DD determine b). With fewer
// the epoch is refused (kInvalidArgument) and the filter is left as it was.
constexpr int kRtkMinSats = 4;
constexpr int kRtkStates = 3 + kRtkMaxSats;            // b_nav_m + one N_sd slot per satellite
constexpr int kRtkMaxRows = 2 * kLambdaMaxAmb + 1;     // DD code + DD carrier + UWB
// BDS B1I wavelength c / 1561.098 MHz (seed 002 uses BDS B1).
constexpr double kBdsB1Wavelength_m = 299792458.0 / 1561.098e6;

using RtkVec3 = Eigen::Matrix<double, 3, 1>;
using RtkMat3 = Eigen::Matrix<double, 3, 3>;
using RtkStateVec = Eigen::Matrix<double, kRtkStates, 1>;
using RtkStateMat = Eigen::Matrix<double, kRtkStates, kRtkStates>;
using RtkRowVec = Eigen::Matrix<double, kRtkMaxRows, 1>;
using RtkRowMat = Eigen::Matrix<double, kRtkMaxRows, kRtkMaxRows>;
using RtkJacobian = Eigen::Matrix<double, kRtkMaxRows, kRtkStates>;

struct RtkParams {
  double lambda_m = kBdsB1Wavelength_m;   // carrier wavelength [m]
  double sigma_code_m = 0.5;               // undifferenced code sigma at zenith [m]
  double sigma_phase_m = 0.003;            // undifferenced carrier sigma at zenith [m]
  double min_elevation_rad = 0.1745329;    // elevation floor of the 1/sin(el) weight (10 deg)
  double sigma_uwb_m = 0.1;                // UWB range sigma [m]
  // The UWB row is used only once the range's linearisation error bound
  // trace(P_bb) / (2 |b|) (curvature of |b| across the baseline uncertainty)
  // is at most this many UWB sigmas: a sanity gate against a baseline whose
  // direction is still metres off. (With uwb_accumulate = true such ranges
  // lock wrong information into the ambiguities: on tuning seeds 1-99, 1, 4
  // and 10 sigmas left 1, 13 and 21 runs never fixed. Per epoch, the default,
  // 1, 4 and no gate gave the same fix rate within 0.6 %, docs/lambda.md.)
  double uwb_max_linearisation_sigmas = 10.0;
  // false (default): the UWB range constrains only the epoch's own solution
  // (float baseline and LAMBDA input) and is not kept in the filter, so a
  // range linearised at a poor baseline cannot lock wrong information into the
  // ambiguities. true: a normal EKF update kept in the state (tuning seeds:
  // more never-fixed runs, docs/lambda.md).
  bool uwb_accumulate = false;
  double uwb_gate_nis = 16.0;              // UWB innovation gate, squared normalised innovation [-]
  double init_sigma_baseline_m = 100.0;    // prior of b at the first epoch [m]
  double init_sigma_amb_cyc = 100.0;       // prior of a new / slipped N_sd around code-minus-carrier [cycles]
  double ratio_threshold = kLambdaDefaultRatio;  // LAMBDA ratio test (seed 002: 3)
  // Carrier fault exclusion (seed 001's locate-and-exclude applied to the DD
  // carrier rows): while the largest normalised carrier innovation exceeds
  // this many sigmas, that satellite's ambiguity (the reference's when more
  // than half the rows fail) restarts from code-minus-carrier. Catches
  // undetected slips and ambiguities absorbed from multipath-biased code.
  double carrier_gate_sigma = 5.0;
  // Residual-based inflation of R (seed 003 eq. 21-25, per epoch and per
  // block): when nu^T S^-1 nu / rows of the DD code or carrier block exceeds
  // this, that block's R is scaled by the ratio. Street-canyon multipath is
  // metres on code where the model says decimetres.
  double adapt_nis_threshold = 2.0;
  // Fewest satellites (reference included) for an integer fix: fewer DD
  // give a weak ratio test (street-canyon tuning seeds, docs/lambda.md).
  int min_fix_sats = 5;
};

// One common satellite, single differences B minus A (see the file comment).
struct RtkSatObs {
  uint16_t sat_id = 0;            // satellite identifier (e.g. BDS PRN), unique in an epoch
  RtkVec3 los_nav = RtkVec3::Zero();  // unit vector receiver -> satellite, nav frame [-]
  double code_sd_m = 0.0;         // P_B - P_A [m]
  double carrier_sd_cyc = 0.0;    // phi_B - phi_A [cycles]
  bool slip = false;              // cycle slip or loss of lock at A or B since the last epoch
};

struct RtkEpoch {
  int n_sats = 0;
  RtkSatObs sats[kRtkMaxSats];
  bool has_uwb = false;
  double uwb_range_m = 0.0;       // tag A - tag B range [m]
};

struct RtkSolution {
  bool valid = false;             // a DD update was made this epoch
  bool fixed = false;             // LAMBDA ratio >= threshold
  int n_amb = 0;                  // DD ambiguities (satellites - 1)
  uint16_t ref_sat_id = 0;        // reference satellite of the DD
  uint16_t amb_sat_id[kLambdaMaxAmb] = {};  // satellite j of DD ambiguity k (N_j - N_ref)
  double ratio = 0.0;             // LAMBDA ratio second/best [-]
  bool uwb_used = false;          // the UWB range entered this epoch's update
  int carrier_resets = 0;         // ambiguities restarted by the carrier fault exclusion this epoch
  double code_r_scale = 1.0;      // R inflation of the DD code block this epoch [-]
  double carrier_r_scale = 1.0;   // R inflation of the DD carrier block this epoch [-]
  Status lambda_status = Status::kOk;
  RtkVec3 b_float_nav_m = RtkVec3::Zero();
  RtkMat3 p_float_m2 = RtkMat3::Zero();
  RtkVec3 b_fixed_nav_m = RtkVec3::Zero();  // valid when fixed
  RtkMat3 p_fixed_m2 = RtkMat3::Zero();
  LambdaVec amb_float_cyc = LambdaVec::Zero();  // DD float ambiguities [cycles]
  LambdaVec amb_fixed_cyc = LambdaVec::Zero();  // LAMBDA best integers [cycles]
};

class RtkBaseline {
 public:
  RtkBaseline() { reset(); }

  // Checks and stores the parameters (positive finite sigmas, wavelength,
  // gates, threshold >= 1) and resets the filter.
  [[nodiscard]] Status configure(const RtkParams& params);
  void reset();

  // Time update (paper (14)): b random walk, P_bb += q dt I with
  // q = relative_motion_psd_m2_s [m^2/s]; ambiguities constant.
  [[nodiscard]] Status predict(double dt_s, double relative_motion_psd_m2_s);

  // Measurement update with one epoch (paper (13), (15)-(19)), then LAMBDA.
  // Refused with kInvalidArgument (filter unchanged) for n_sats outside
  // [kRtkMinSats, kRtkMaxSats], non-finite inputs, a line of sight that is not
  // a unit vector, duplicate satellite ids or a non-positive UWB range;
  // kSingular when the innovation covariance is not positive definite. A
  // LAMBDA failure still leaves a valid float solution (sol.lambda_status).
  [[nodiscard]] Status update(const RtkEpoch& epoch, RtkSolution& sol);

  // Measurement model of an epoch at state x (for tests): predicted rows and
  // the Jacobian d h / d x, rows ordered DD code (n-1), DD carrier [m] (n-1),
  // UWB; returns the number of rows (0 on invalid input). ref = index of the
  // reference satellite in the epoch.
  int model(const RtkEpoch& epoch, int ref, const RtkStateVec& x, RtkRowVec& h, RtkJacobian& jac) const;

  const RtkStateVec& state() const { return x_; }
  const RtkStateMat& covariance() const { return p_; }
  bool initialised() const { return initialised_; }
  // Slot of a satellite id in the state (-1 when not tracked).
  int slot_of(uint16_t sat_id) const;

 private:
  Status check(const RtkEpoch& epoch) const;
  int choose_slot(uint16_t sat_id);
  void reset_slot(int slot, double n_sd_cyc);
  double sigma_sd2(const RtkVec3& los, double sigma0) const;
  void exclude_carrier_faults(const RtkEpoch& epoch, int ref, RtkSolution& sol);
  double block_nis(int first_row, int rows);

  RtkParams params_;
  bool initialised_ = false;
  RtkStateVec x_;
  RtkStateMat p_;
  uint16_t slot_id_[kRtkMaxSats] = {};
  bool slot_used_[kRtkMaxSats] = {};
  uint32_t slot_seen_[kRtkMaxSats] = {};  // epoch counter at last use
  uint32_t epoch_count_ = 0;
  int epoch_slot_[kRtkMaxSats] = {};       // slot of each satellite of the current epoch
  bool restarted_[kRtkMaxSats] = {};       // its ambiguity restarted this epoch (new or slipped)
  // Scratch.
  RtkRowVec h_, z_;
  RtkJacobian jac_;
  RtkRowMat r_, s_;
  Eigen::Matrix<double, kRtkStates, kRtkMaxRows> k_;
  RtkJacobian hp_;                      // H P
  Eigen::LLT<RtkRowMat> llt_s_;         // innovation covariance factor
  Eigen::LLT<LambdaMat> llt_q_;         // Q_NN factor (fixed baseline)
  LambdaMat s_blk_;                     // one block (code or carrier) of S, padded with identity
  LambdaVec nu_blk_;
  Eigen::LLT<LambdaMat> llt_blk_;
  RtkStateMat tmp_;
  RtkStateVec x_dd_;     // state after the DD update, before the UWB range
  RtkStateMat p_dd_;
  RtkStateMat p_new_;
  RtkStateVec x_save_;   // state before an update, restored when it fails
  RtkStateMat p_save_;
  Eigen::Matrix<double, kLambdaMaxAmb, kRtkStates> d_amb_;  // DD ambiguities = d_amb_ x
  LambdaMat q_nn_;
  Eigen::Matrix<double, 3, kLambdaMaxAmb> q_bn_;
  LambdaSolver lambda_;
  LambdaFix fix_;
};

}  // namespace uwbnav

#endif  // UWBNAV_LAMBDA
