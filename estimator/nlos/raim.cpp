// Seed 001 RAIM: LS residuals, chi-square global test, normal local test, exclusion.
#include "estimator/nlos/raim.hpp"

#include <cmath>

#include <Eigen/Dense>

#include "estimator/nlos/chi_square.hpp"

namespace uwbnav {

void raim_compute_thresholds(float p_fa, float p_fa_local, RaimThresholds& out) {
  out.chi2_by_dof[0] = 0.0F;
  for (size_t dof = 1; dof <= kRaimMaxRanges; ++dof) {
    out.chi2_by_dof[dof] = chi_square_upper_quantile(p_fa, static_cast<int>(dof));
  }
  out.local = normal_upper_quantile(0.5F * p_fa_local);
}

namespace {

// Standardised residuals w_i = v_i / sqrt(Qvv_ii), Qvv = W^-1 - H (H^T W H)^-1 H^T,
// H the range Jacobian at the fix (x, y[, z]); W = diag(1/sigma^2).
template <int kUnknowns>
bool standardised_residuals(const LsRange* r, const size_t* idx, size_t m, const LsFix& fix,
                            float* w_out) {
  using Mat = Eigen::Matrix<float, kUnknowns, kUnknowns>;
  using Vec = Eigen::Matrix<float, kUnknowns, 1>;
  Vec h_rows[kRaimMaxRanges];
  Mat n_mat = Mat::Zero();
  for (size_t j = 0; j < m; ++j) {
    const LsRange& rr = r[idx[j]];
    const float dx = fix.pos_nav_m.x - rr.anchor_pos_nav_m.x;
    const float dy = fix.pos_nav_m.y - rr.anchor_pos_nav_m.y;
    const float dz = fix.pos_nav_m.z - rr.anchor_pos_nav_m.z;
    const float dist = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(dist > 1e-3F)) return false;
    Vec h;
    h(0) = dx / dist;
    h(1) = dy / dist;
    if (kUnknowns == 3) h(kUnknowns - 1) = dz / dist;
    h_rows[j] = h;
    n_mat += h * h.transpose() / (rr.sigma_m * rr.sigma_m);
  }
  Eigen::LDLT<Mat> ldlt(n_mat);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-7F)) return false;
  // Column by column: a matrix right-hand side takes Eigen's blocked
  // triangular solver, which may allocate; vector solves never do.
  Mat n_inv;
  for (int c = 0; c < kUnknowns; ++c) n_inv.col(c) = ldlt.solve(Vec::Unit(c));
  for (size_t j = 0; j < m; ++j) {
    const LsRange& rr = r[idx[j]];
    const float qvv = rr.sigma_m * rr.sigma_m - h_rows[j].dot(n_inv * h_rows[j]);
    const float v = fix.residual_m[j];
    w_out[j] = qvv > 1e-12F ? std::fabs(v) / std::sqrt(qvv) : 0.0F;
  }
  return true;
}

}  // namespace

Status raim_run(const LsRange* ranges, size_t n, const LsOptions& options,
                const RaimThresholds& thresholds, RaimResult& out) {
  out = RaimResult{};
  if (n > kRaimMaxRanges) return Status::kInvalidArgument;
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(ranges[i].range_m) || !(ranges[i].sigma_m > 0.0F)) return Status::kInvalidArgument;
  }
  const size_t unknowns = options.two_d ? 2U : 3U;
  size_t idx[kRaimMaxRanges];
  LsRange active[kRaimMaxRanges];
  size_t m = 0;
  for (size_t i = 0; i < n; ++i) idx[m++] = i;

  LsOptions opt = options;
  while (m > unknowns) {
    for (size_t j = 0; j < m; ++j) active[j] = ranges[idx[j]];
    LsFix fix;
    if (!ok(ls_taylor_solve(active, m, opt, fix)) || !fix.converged) return Status::kOk;
    const size_t dof = m - unknowns;
    out.available = true;
    out.fix = fix;
    out.test_statistic = fix.weighted_ssr;
    out.threshold = thresholds.chi2_by_dof[dof];
    // Global test (seed 001): SSR of the weighted residuals against chi2(1 - p_fa, n - unknowns).
    if (!(fix.weighted_ssr > thresholds.chi2_by_dof[dof])) {
      out.consistent = true;
      float w[kRaimMaxRanges] = {};
      size_t self_idx[kRaimMaxRanges];
      for (size_t j = 0; j < m; ++j) self_idx[j] = j;
      if (opt.two_d ? standardised_residuals<2>(active, self_idx, m, fix, w)
                    : standardised_residuals<3>(active, self_idx, m, fix, w)) {
        for (size_t j = 0; j < m; ++j) out.std_residual[idx[j]] = w[j];
      }
      return Status::kOk;
    }
    // Local test: the largest standardised residual above the normal threshold is the fault.
    // With dof 1 all standardised residuals are equal: the fault cannot be located.
    if (dof < 2) return Status::kOk;
    float w[kRaimMaxRanges] = {};
    size_t self_idx[kRaimMaxRanges];
    for (size_t j = 0; j < m; ++j) self_idx[j] = j;
    const bool have_w = opt.two_d ? standardised_residuals<2>(active, self_idx, m, fix, w)
                                  : standardised_residuals<3>(active, self_idx, m, fix, w);
    if (!have_w) return Status::kOk;
    size_t worst = 0;
    for (size_t j = 0; j < m; ++j) {
      out.std_residual[idx[j]] = w[j];
      if (w[j] > w[worst]) worst = j;
    }
    if (!(w[worst] > thresholds.local)) return Status::kOk;
    out.excluded[idx[worst]] = true;
    ++out.num_excluded;
    for (size_t j = worst; j + 1 < m; ++j) idx[j] = idx[j + 1];
    --m;
    opt.has_initial_guess = true;
    opt.initial_guess_nav_m = fix.pos_nav_m;
  }
  return Status::kOk;
}

}  // namespace uwbnav
