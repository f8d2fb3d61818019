// Carrier-phase relative positioning (baseline + DD ambiguities, UWB range,
// LAMBDA fix) between two vehicles; model and conventions in rtk_baseline.hpp,
// docs/lambda.md "Relative positioning with double differences". Seed paper 002.
#include "estimator/rtk_baseline.hpp"

#if UWBNAV_LAMBDA

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace uwbnav {

namespace {

bool finite3(const RtkVec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

constexpr double kUnitTolerance = 1e-6;   // |e| must be 1 within this
constexpr double kMinUwbBaseline_m = 0.5;  // UWB row linearised only beyond this |b|
constexpr int kUwbIterations = 3;          // iterated EKF passes of the scalar UWB update

}  // namespace

Status RtkBaseline::configure(const RtkParams& params) {
  const double pos[] = {params.lambda_m,           params.sigma_code_m,         params.sigma_phase_m,
                        params.sigma_uwb_m,        params.init_sigma_baseline_m, params.init_sigma_amb_cyc,
                        params.uwb_max_linearisation_sigmas, params.uwb_gate_nis};
  for (double v : pos) {
    if (!std::isfinite(v) || v <= 0.0) return Status::kInvalidArgument;
  }
  if (!std::isfinite(params.min_elevation_rad) || params.min_elevation_rad <= 0.0 ||
      params.min_elevation_rad >= 1.5707963267948966) {
    return Status::kInvalidArgument;
  }
  if (!std::isfinite(params.ratio_threshold) || params.ratio_threshold < 1.0) return Status::kInvalidArgument;
  if (!std::isfinite(params.carrier_gate_sigma) || params.carrier_gate_sigma < 1.0 ||
      !std::isfinite(params.adapt_nis_threshold) || params.adapt_nis_threshold < 1.0 ||
      params.min_fix_sats < kRtkMinSats || params.min_fix_sats > kRtkMaxSats) {
    return Status::kInvalidArgument;
  }
  params_ = params;
  reset();
  return Status::kOk;
}

void RtkBaseline::reset() {
  initialised_ = false;
  x_.setZero();
  p_.setZero();
  for (int i = 0; i < kRtkMaxSats; ++i) {
    slot_id_[i] = 0;
    slot_used_[i] = false;
    slot_seen_[i] = 0;
    epoch_slot_[i] = -1;
  }
  epoch_count_ = 0;
}

Status RtkBaseline::predict(double dt_s, double relative_motion_psd_m2_s) {
  if (!std::isfinite(dt_s) || dt_s < 0.0 || !std::isfinite(relative_motion_psd_m2_s) ||
      relative_motion_psd_m2_s < 0.0) {
    return Status::kInvalidArgument;
  }
  if (!initialised_) return Status::kOk;
  // Paper (14): b_k+1 = b_k + w_k (random walk), N_k+1 = N_k.
  const double q = relative_motion_psd_m2_s * dt_s;
  for (int i = 0; i < 3; ++i) p_(i, i) += q;
  return Status::kOk;
}

int RtkBaseline::slot_of(uint16_t sat_id) const {
  for (int i = 0; i < kRtkMaxSats; ++i) {
    if (slot_used_[i] && slot_id_[i] == sat_id) return i;
  }
  return -1;
}

int RtkBaseline::choose_slot(uint16_t sat_id) {
  int best = -1;
  for (int i = 0; i < kRtkMaxSats; ++i) {
    if (!slot_used_[i]) {
      best = i;
      break;
    }
    if (slot_seen_[i] == epoch_count_) continue;  // in use this epoch
    if (best < 0 || slot_seen_[i] < slot_seen_[best]) best = i;
  }
  if (best >= 0) {
    slot_used_[best] = true;
    slot_id_[best] = sat_id;
    slot_seen_[best] = epoch_count_;
  }
  return best;
}

void RtkBaseline::reset_slot(int slot, double n_sd_cyc) {
  const int k = 3 + slot;
  x_(k) = n_sd_cyc;
  p_.row(k).setZero();
  p_.col(k).setZero();
  p_(k, k) = params_.init_sigma_amb_cyc * params_.init_sigma_amb_cyc;
}

double RtkBaseline::sigma_sd2(const RtkVec3& los, double sigma0) const {
  // Undifferenced sigma0 / sin(el) per receiver, two receivers in the SD.
  const double s = std::max(std::min(los.z(), 1.0), std::sin(params_.min_elevation_rad));
  const double sig = sigma0 / s;
  return 2.0 * sig * sig;
}

double RtkBaseline::block_nis(int first_row, int rows) {
  // nu^T S^-1 nu over rows [first_row, first_row + rows) of the current model.
  s_blk_.setIdentity();
  nu_blk_.setZero();
  s_blk_.topLeftCorner(rows, rows) = s_.block(first_row, first_row, rows, rows);
  nu_blk_.head(rows) = z_.segment(first_row, rows) - h_.segment(first_row, rows);
  llt_blk_.compute(s_blk_);
  if (llt_blk_.info() != Eigen::Success) return 0.0;
  return nu_blk_.dot(llt_blk_.solve(nu_blk_));
}

void RtkBaseline::exclude_carrier_faults(const RtkEpoch& epoch, int ref, RtkSolution& sol) {
  // Locate and exclude (seed 001 applied to the carrier rows): the largest
  // normalised DD carrier innovation above the gate names the satellite whose
  // ambiguity restarts; more than half the rows above it name the reference.
  const int n = epoch.n_sats;
  const int m = n - 1;
  for (int pass = 0; pass < n; ++pass) {
    hp_.noalias() = jac_ * p_;
    s_.noalias() = hp_ * jac_.transpose();
    s_ += r_;
    int worst = -1, failing = 0;
    double worst_z = params_.carrier_gate_sigma;
    for (int k = 0; k < m; ++k) {
      const double var = s_(m + k, m + k);
      if (!(var > 0.0)) continue;
      const double zn = std::fabs(z_(m + k) - h_(m + k)) / std::sqrt(var);
      if (zn > params_.carrier_gate_sigma) ++failing;
      if (zn > worst_z) {
        worst_z = zn;
        worst = k;
      }
    }
    if (worst < 0) return;
    int sat = ref;
    if (2 * failing <= m) {
      sat = worst < ref ? worst : worst + 1;  // row k is satellite k, skipping the reference
    }
    const RtkSatObs& s = epoch.sats[sat];
    reset_slot(epoch_slot_[sat], s.carrier_sd_cyc - s.code_sd_m / params_.lambda_m);
    ++sol.carrier_resets;
    if (model(epoch, ref, x_, h_, jac_) != 2 * m) return;
  }
}

Status RtkBaseline::check(const RtkEpoch& epoch) const {
  if (epoch.n_sats < kRtkMinSats || epoch.n_sats > kRtkMaxSats) return Status::kInvalidArgument;
  for (int i = 0; i < epoch.n_sats; ++i) {
    const RtkSatObs& s = epoch.sats[i];
    if (!finite3(s.los_nav) || !std::isfinite(s.code_sd_m) || !std::isfinite(s.carrier_sd_cyc)) {
      return Status::kInvalidArgument;
    }
    if (std::fabs(s.los_nav.norm() - 1.0) > kUnitTolerance) return Status::kInvalidArgument;
    for (int j = 0; j < i; ++j) {
      if (epoch.sats[j].sat_id == s.sat_id) return Status::kInvalidArgument;
    }
  }
  if (epoch.has_uwb && (!std::isfinite(epoch.uwb_range_m) || epoch.uwb_range_m <= 0.0)) {
    return Status::kInvalidArgument;
  }
  return Status::kOk;
}

int RtkBaseline::model(const RtkEpoch& epoch, int ref, const RtkStateVec& x, RtkRowVec& h,
                       RtkJacobian& jac) const {
  h.setZero();
  jac.setZero();
  const int n = epoch.n_sats;
  if (n < 2 || n > kRtkMaxSats || ref < 0 || ref >= n) return 0;
  const int slot_r = slot_of(epoch.sats[ref].sat_id);
  if (slot_r < 0) return 0;
  const int m = n - 1;
  const RtkVec3 b = x.head<3>();
  const RtkVec3& e_r = epoch.sats[ref].los_nav;
  const double lam = params_.lambda_m;
  int k = 0;
  for (int j = 0; j < n; ++j) {
    if (j == ref) continue;
    const int slot_j = slot_of(epoch.sats[j].sat_id);
    if (slot_j < 0) return 0;
    const RtkVec3 g = -(epoch.sats[j].los_nav - e_r);  // d(DD range)/db, paper (11)
    // Paper (5): DD code.
    h(k) = g.dot(b);
    jac.block<1, 3>(k, 0) = g.transpose();
    // Paper (6): DD carrier [m].
    h(m + k) = g.dot(b) + lam * (x(3 + slot_j) - x(3 + slot_r));
    jac.block<1, 3>(m + k, 0) = g.transpose();
    jac(m + k, 3 + slot_j) = lam;
    jac(m + k, 3 + slot_r) = -lam;
    ++k;
  }
  int rows = 2 * m;
  if (epoch.has_uwb) {
    // Paper (9)/(12): UWB range = |b| (lever arms zero), Jacobian b^T/|b|.
    const double len = b.norm();
    h(rows) = len;
    if (len > 0.0) jac.block<1, 3>(rows, 0) = (b / len).transpose();
    ++rows;
  }
  return rows;
}

Status RtkBaseline::update(const RtkEpoch& epoch, RtkSolution& sol) {
  sol = RtkSolution{};
  const Status st = check(epoch);
  if (!ok(st)) return st;

  // Save for a refused update (slots and state restored together).
  x_save_ = x_;
  p_save_ = p_;
  uint16_t id_save[kRtkMaxSats];
  bool used_save[kRtkMaxSats];
  uint32_t seen_save[kRtkMaxSats];
  for (int i = 0; i < kRtkMaxSats; ++i) {
    id_save[i] = slot_id_[i];
    used_save[i] = slot_used_[i];
    seen_save[i] = slot_seen_[i];
  }
  const bool init_save = initialised_;
  const uint32_t count_save = epoch_count_;
  auto restore = [&]() {
    sol = RtkSolution{};
    x_ = x_save_;
    p_ = p_save_;
    for (int i = 0; i < kRtkMaxSats; ++i) {
      slot_id_[i] = id_save[i];
      slot_used_[i] = used_save[i];
      slot_seen_[i] = seen_save[i];
    }
    initialised_ = init_save;
    epoch_count_ = count_save;
  };

  ++epoch_count_;
  if (!initialised_) {
    x_.setZero();
    p_.setZero();
    const double v = params_.init_sigma_baseline_m * params_.init_sigma_baseline_m;
    for (int i = 0; i < 3; ++i) p_(i, i) = v;
    initialised_ = true;
  }
  const int n = epoch.n_sats;
  // Pass 1: satellites already tracked keep their slot.
  for (int i = 0; i < n; ++i) {
    epoch_slot_[i] = slot_of(epoch.sats[i].sat_id);
    if (epoch_slot_[i] >= 0) slot_seen_[epoch_slot_[i]] = epoch_count_;
  }
  // Pass 2: new satellites take a free or the stalest slot; new or slipped
  // ambiguities restart from code-minus-carrier with a wide prior.
  for (int i = 0; i < n; ++i) {
    const RtkSatObs& s = epoch.sats[i];
    const bool is_new = epoch_slot_[i] < 0;
    if (is_new) epoch_slot_[i] = choose_slot(s.sat_id);
    if (epoch_slot_[i] < 0) {  // cannot happen with n <= kRtkMaxSats
      restore();
      return Status::kFull;
    }
    restarted_[i] = is_new || s.slip;
    if (restarted_[i]) reset_slot(epoch_slot_[i], s.carrier_sd_cyc - s.code_sd_m / params_.lambda_m);
  }
  // Reference: highest elevation among the satellites whose ambiguity did not
  // restart this epoch (new or slipped): a fresh 100-cycle prior on the
  // reference would hide every carrier row from the fault test.
  int ref = -1;
  for (int pass = 0; pass < 2 && ref < 0; ++pass) {
    for (int i = 0; i < n; ++i) {
      if (pass == 0 && restarted_[i]) continue;
      if (ref < 0 || epoch.sats[i].los_nav.z() > epoch.sats[ref].los_nav.z()) ref = i;
    }
  }
  const int m = n - 1;
  const double lam = params_.lambda_m;

  // --- DD code and carrier update (paper (13), (15)-(19)) ---
  RtkEpoch dd_only = epoch;  // copy on the stack: ~1 KiB
  dd_only.has_uwb = false;
  const int rows = model(dd_only, ref, x_, h_, jac_);
  if (rows != 2 * m) {
    restore();
    return Status::kInvalidArgument;
  }
  z_.setZero();
  {
    int k = 0;
    for (int j = 0; j < n; ++j) {
      if (j == ref) continue;
      z_(k) = epoch.sats[j].code_sd_m - epoch.sats[ref].code_sd_m;
      z_(m + k) = lam * (epoch.sats[j].carrier_sd_cyc - epoch.sats[ref].carrier_sd_cyc);
      ++k;
    }
  }
  // DD covariance D Sigma_SD D^T: var_j + var_r on the diagonal, var_r off it.
  r_.setIdentity();  // padding rows: unit variance, zero Jacobian, zero innovation
  {
    const double vc_r = sigma_sd2(epoch.sats[ref].los_nav, params_.sigma_code_m);
    const double vp_r = sigma_sd2(epoch.sats[ref].los_nav, params_.sigma_phase_m);
    int k = 0;
    for (int j = 0; j < n; ++j) {
      if (j == ref) continue;
      for (int l = 0; l < m; ++l) {
        r_(k, l) = vc_r;
        r_(m + k, m + l) = vp_r;
      }
      r_(k, k) = vc_r + sigma_sd2(epoch.sats[j].los_nav, params_.sigma_code_m);
      r_(m + k, m + k) = vp_r + sigma_sd2(epoch.sats[j].los_nav, params_.sigma_phase_m);
      ++k;
    }
  }
  exclude_carrier_faults(dd_only, ref, sol);
  // Residual-based inflation of R per block (seed 003 eq. 21-25).
  hp_.noalias() = jac_ * p_;
  s_.noalias() = hp_ * jac_.transpose();
  s_ += r_;
  for (int block = 0; block < 2; ++block) {
    const double a = block_nis(block * m, m) / static_cast<double>(m);
    if (!(a > params_.adapt_nis_threshold)) continue;
    r_.block(block * m, block * m, m, m) *= a;
    s_.block(block * m, block * m, m, m) += (a - 1.0) / a * r_.block(block * m, block * m, m, m);
    (block == 0 ? sol.code_r_scale : sol.carrier_r_scale) = a;
  }
  llt_s_.compute(s_);
  if (llt_s_.info() != Eigen::Success) {
    restore();
    return Status::kSingular;
  }
  // K = P H^T S^-1 = (S^-1 H P)^T
  llt_s_.solveInPlace(hp_);
  k_ = hp_.transpose();
  const RtkRowVec innov = z_ - h_;
  x_ += k_ * innov;
  // Joseph form.
  tmp_ = RtkStateMat::Identity();
  tmp_.noalias() -= k_ * jac_;
    p_new_.noalias() = tmp_ * p_ * tmp_.transpose();
  p_new_.noalias() += k_ * r_ * k_.transpose();
  p_ = 0.5 * (p_new_ + p_new_.transpose());

  // --- UWB range (paper (9)), scalar iterated EKF linearised at the DD solution ---
  x_dd_ = x_;
  p_dd_ = p_;
  const double len_dd = x_.head<3>().norm();
  const double lin_err_m = len_dd > kMinUwbBaseline_m ? p_.topLeftCorner<3, 3>().trace() / (2.0 * len_dd) : 1e300;
  bool uwb_ok = epoch.has_uwb && lin_err_m <= params_.uwb_max_linearisation_sigmas * params_.sigma_uwb_m;
  if (uwb_ok) {
    // Innovation gate at the DD solution.
    const RtkVec3 u = x_.head<3>() / len_dd;
    const double s = u.dot(p_.topLeftCorner<3, 3>() * u) + params_.sigma_uwb_m * params_.sigma_uwb_m;
    const double nu = epoch.uwb_range_m - len_dd;
    uwb_ok = nu * nu <= params_.uwb_gate_nis * s;
  }
  if (uwb_ok) {
    const RtkStateVec x0 = x_;
    RtkStateVec xi = x_;
    Eigen::Matrix<double, 1, kRtkStates> hrow;
    Eigen::Matrix<double, kRtkStates, 1> kg;
    bool used = false;
    for (int it = 0; it < kUwbIterations; ++it) {
      const RtkVec3 b = xi.head<3>();
      const double len = b.norm();
      if (!(len > kMinUwbBaseline_m)) break;
      hrow.setZero();
      hrow.head<3>() = (b / len).transpose();
      const double s = (hrow * p_ * hrow.transpose())(0, 0) + params_.sigma_uwb_m * params_.sigma_uwb_m;
      if (!(s > 0.0)) break;
      kg = p_ * hrow.transpose() / s;
      const double resid = epoch.uwb_range_m - len - (hrow * (x0 - xi))(0, 0);
      xi = x0 + kg * resid;
      used = true;
    }
    // The final Jacobian needs |b| above the linearisation floor at the last
    // iterate; otherwise the range is skipped for this epoch (the DD update stands).
    if (used && !(xi.head<3>().norm() > kMinUwbBaseline_m)) used = false;
    if (used) {
      const RtkVec3 b = xi.head<3>();
      hrow.setZero();
      hrow.head<3>() = (b / b.norm()).transpose();
      const double s = (hrow * p_ * hrow.transpose())(0, 0) + params_.sigma_uwb_m * params_.sigma_uwb_m;
      kg = p_ * hrow.transpose() / s;
      x_ = xi;
      sol.uwb_used = true;
      tmp_ = RtkStateMat::Identity();
      tmp_.noalias() -= kg * hrow;
      p_new_.noalias() = tmp_ * p_ * tmp_.transpose();
      p_new_.noalias() += kg * (params_.sigma_uwb_m * params_.sigma_uwb_m) * kg.transpose();
      p_ = 0.5 * (p_new_ + p_new_.transpose());
    }
  }
  if (!x_.allFinite() || !p_.allFinite()) {
    restore();
    return Status::kNotFinite;
  }

  // --- Solution, float ---
  sol.valid = true;
  sol.b_float_nav_m = x_.head<3>();
  sol.p_float_m2 = p_.topLeftCorner<3, 3>();
  sol.n_amb = m;
  sol.ref_sat_id = epoch.sats[ref].sat_id;
  // DD ambiguities a = D N_sd for the current reference.
  d_amb_.setZero();
  {
    int k = 0;
    for (int j = 0; j < n; ++j) {
      if (j == ref) continue;
      sol.amb_sat_id[k] = epoch.sats[j].sat_id;
      d_amb_(k, 3 + epoch_slot_[j]) = 1.0;
      d_amb_(k, 3 + epoch_slot_[ref]) = -1.0;
      ++k;
    }
  }
  sol.amb_float_cyc = d_amb_ * x_;
  const bool may_fix = n >= params_.min_fix_sats;
  q_nn_.noalias() = d_amb_ * p_ * d_amb_.transpose();
  q_bn_.noalias() = p_.topRows<3>() * d_amb_.transpose();

  // --- LAMBDA (paper: LAMBDA, fixed when RATIO > 3) ---
  sol.lambda_status = lambda_.solve(sol.amb_float_cyc, q_nn_, m, fix_, params_.ratio_threshold);
  if (ok(sol.lambda_status)) {
    sol.ratio = fix_.ratio;
    sol.amb_fixed_cyc = fix_.best_cyc;
    if (fix_.fixed && may_fix) {
      // b_fix = b - Q_bN Q_NN^-1 (a_float - a_fixed), P_fix = P_bb - Q_bN Q_NN^-1 Q_Nb.
      for (int i = m; i < kLambdaMaxAmb; ++i) q_nn_(i, i) = 1.0;  // padding rows: unit, uncoupled
      llt_q_.compute(q_nn_);
      const auto& lq = llt_q_;
      if (lq.info() == Eigen::Success) {
        LambdaVec da = sol.amb_float_cyc - fix_.best_cyc;
        for (int i = m; i < kLambdaMaxAmb; ++i) da(i) = 0.0;
        const LambdaVec w = lq.solve(da);
        sol.b_fixed_nav_m = sol.b_float_nav_m - q_bn_ * w;
        const Eigen::Matrix<double, kLambdaMaxAmb, 3> qnb = q_bn_.transpose();
        const Eigen::Matrix<double, kLambdaMaxAmb, 3> u = lq.solve(qnb);
        sol.p_fixed_m2 = sol.p_float_m2 - q_bn_ * u;
        sol.fixed = sol.b_fixed_nav_m.allFinite();
      }
    }
  }
  if (sol.uwb_used && !params_.uwb_accumulate) {
    x_ = x_dd_;
    p_ = p_dd_;
  }
  return Status::kOk;
}

}  // namespace uwbnav

#endif  // UWBNAV_LAMBDA
