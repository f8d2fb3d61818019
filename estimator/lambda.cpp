// LAMBDA integer least squares: L^T D L factorisation [JT96], decorrelation by
// integer Gauss transformations and permutations (the reduction of [CYZ05],
// [JT96]), depth-first search with shrinking ellipsoid and Schnorr-Euchner
// enumeration [CYZ05], back-transformation and the ratio test. Double
// precision, static memory. References in lambda.hpp; the equations are
// written out here (not numbered after the papers).
#include "estimator/lambda.hpp"

#if UWBNAV_LAMBDA

#include <cmath>
#include <limits>

namespace uwbnav {
namespace {

// A permutation of levels k, k+1 is made only when it shrinks d_{k+1} by more
// than this share (the strict test delta < d_{k+1} of [CYZ05] could cycle on
// rounding when delta == d_{k+1} to the last bit; RTKLIB uses an absolute 1e-6).
constexpr double kSwapMargin = 1e-6;

}  // namespace

LambdaSolver::LambdaSolver() {
  l_.setZero();
  d_.setZero();
  z_.setIdentity();
  z_inv_.setIdentity();
  a_round_.setZero();
  z_hat_.setZero();
  z_try_.setZero();
  z_cond_.setZero();
  step_.setZero();
  partial_.setZero();
  for (auto& c : cand_) c.setZero();
}

void LambdaSolver::set_step_caps(uint32_t max_reduction_steps, uint32_t max_search_steps) {
  max_reduction_steps_ = max_reduction_steps > 0 ? max_reduction_steps : kLambdaMaxReductionSteps;
  max_search_steps_ = max_search_steps > 0 ? max_search_steps : kLambdaMaxSearchSteps;
}

Status LambdaSolver::solve(const LambdaVec& float_amb_cyc, const LambdaMat& cov_cyc2, int n, LambdaFix& fix,
                           double ratio_threshold) {
  fix = LambdaFix{};
  n_ = 0;
  if (n < 1 || n > kLambdaMaxAmb) return Status::kInvalidArgument;
  if (!std::isfinite(ratio_threshold) || ratio_threshold < 1.0) return Status::kInvalidArgument;
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(float_amb_cyc(i)) || !(std::fabs(float_amb_cyc(i)) < kLambdaMaxAbsAmb_cyc)) {
      return Status::kInvalidArgument;
    }
    for (int j = 0; j <= i; ++j) {
      if (!std::isfinite(cov_cyc2(i, j))) return Status::kInvalidArgument;
    }
  }
  n_ = n;

  // The problem is invariant under integer shifts: solve for the fraction
  // a_hat - round(a_hat) and add round(a_hat) back (keeps the search in small
  // numbers when the ambiguities are 1e6..1e9 cycles, as RTKLIB's are).
  LambdaVec frac = LambdaVec::Zero();
  for (int i = 0; i < n; ++i) {
    a_round_(i) = std::round(float_amb_cyc(i));
    frac(i) = float_amb_cyc(i) - a_round_(i);
  }
  z_.setIdentity();
  z_inv_.setIdentity();

  Status s = factorise(cov_cyc2);
  if (s == Status::kOk) s = reduce(fix);
  if (s == Status::kOk) {
    // Decorrelated float ambiguities z_hat = Z^T a_hat [T95] (of the fraction).
    z_hat_.setZero();
    for (int k = 0; k < n; ++k) {
      double sum = 0.0;
      for (int m = 0; m < n; ++m) sum += z_(m, k) * frac(m);
      z_hat_(k) = sum;
    }
    s = search(fix);
  }
  if (s != Status::kOk) {
    n_ = 0;  // fix still holds its reset values and the step counters only
    return s;
  }

  // Back-transformation a = Z^-T z [T95], plus the shift. Z^-1 is
  // integer, so the candidates are exact integers (|entries| < 2^52 checked).
  fix.n = n;
  const int best = cand_norm_[1] < cand_norm_[0] ? 1 : 0;
  const int second = 1 - best;
  for (int k = 0; k < n; ++k) {
    double a1 = a_round_(k);
    double a2 = a_round_(k);
    for (int m = 0; m < n; ++m) {
      a1 += z_inv_(m, k) * cand_[best](m);
      a2 += z_inv_(m, k) * cand_[second](m);
    }
    fix.best_cyc(k) = a1;
    fix.second_cyc(k) = a2;
  }
  fix.best_sq_norm = cand_norm_[best];
  fix.second_sq_norm = cand_norm_[second];
  // Ratio test (seed 002; RTKLIB's definition):
  // accept the best when ||a_hat - a_2||^2 / ||a_hat - a_1||^2 >= threshold.
  fix.ratio = fix.second_sq_norm < kLambdaMaxRatio * fix.best_sq_norm ? fix.second_sq_norm / fix.best_sq_norm
                                                                       : kLambdaMaxRatio;
  fix.fixed = fix.ratio >= ratio_threshold;
  return Status::kOk;
}

// Q = L^T D L with L unit lower triangular and D diagonal [JT96],
// computed from the last row up: d_i = A_ii, L_ij = A_ij / d_i (j < i), then
// A_jk <- A_jk - L_ij L_ik d_i for k <= j < i, where A starts as Q. d_i is the
// variance of a_i conditioned on a_0..a_{i-1}. In place in l_ (lower triangle).
Status LambdaSolver::factorise(const LambdaMat& cov_cyc2) {
  const int n = n_;
  l_.setZero();
  d_.setZero();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j) l_(i, j) = cov_cyc2(i, j);
  }
  for (int i = n - 1; i >= 0; --i) {
    const double pivot = l_(i, i);
    // Not positive definite, or so close to singular that the pivot has no
    // correct digits left (kLambdaMinPivotRatio).
    if (!(pivot > 0.0) || !(pivot >= kLambdaMinPivotRatio * cov_cyc2(i, i))) return kLambdaNotPositiveDefinite;
    d_(i) = pivot;
    for (int j = 0; j < i; ++j) l_(i, j) /= pivot;
    for (int j = 0; j < i; ++j) {
      const double lij_d = l_(i, j) * pivot;
      for (int k = 0; k <= j; ++k) l_(j, k) -= lij_d * l_(i, k);
    }
    l_(i, i) = 1.0;
  }
  return Status::kOk;
}

// Integer Gauss transformation [JT96; CYZ05]:
// G = I - mu e_i e_j^T with mu = round(L_ij), i > j, applied as
//   L <- L G   (column j -= mu column i, rows >= i: |L_ij| <= 1/2 after),
//   Z <- Z G   (column j -= mu column i),  Z^-1 <- G^-1 Z^-1 (row i += mu row j).
// D does not change; G is unimodular, so Z stays integer with |det Z| = 1.
void LambdaSolver::integer_gauss(int i, int j) {
  const double mu = std::round(l_(i, j));
  if (mu == 0.0) return;
  for (int r = i; r < n_; ++r) l_(r, j) -= mu * l_(r, i);
  for (int r = 0; r < n_; ++r) z_(r, j) -= mu * z_(r, i);
  for (int c = 0; c < n_; ++c) z_inv_(i, c) += mu * z_inv_(j, c);
}

// Permutation of levels k and k+1 [JT96; CYZ05],
// with l = L_{k+1,k}, delta = d_k + l^2 d_{k+1}, eta = d_k / delta,
// lambda = d_{k+1} l / delta:
//   d_k' = eta d_{k+1},  d_{k+1}' = delta,  L_{k+1,k}' = lambda,
//   [L_kj'; L_{k+1,j}'] = [-l 1; eta lambda] [L_kj; L_{k+1,j}]   for j < k,
//   L_ik <-> L_{i,k+1} for i > k+1;  columns k, k+1 of Z and rows of Z^-1 swap.
// Both new conditional variances lie in [d_k, d_{k+1}]: the spread of D never grows.
void LambdaSolver::permute(int k, double delta) {
  const double l = l_(k + 1, k);
  const double eta = d_(k) / delta;
  const double lambda = d_(k + 1) * l / delta;
  d_(k) = eta * d_(k + 1);
  d_(k + 1) = delta;
  for (int j = 0; j < k; ++j) {
    const double lk = l_(k, j);
    const double lk1 = l_(k + 1, j);
    l_(k, j) = lk1 - l * lk;
    l_(k + 1, j) = eta * lk + lambda * lk1;
  }
  l_(k + 1, k) = lambda;
  for (int i = k + 2; i < n_; ++i) {
    const double t = l_(i, k);
    l_(i, k) = l_(i, k + 1);
    l_(i, k + 1) = t;
  }
  for (int r = 0; r < n_; ++r) {
    const double t = z_(r, k);
    z_(r, k) = z_(r, k + 1);
    z_(r, k + 1) = t;
  }
  for (int c = 0; c < n_; ++c) {
    const double t = z_inv_(k, c);
    z_inv_(k, c) = z_inv_(k + 1, c);
    z_inv_(k + 1, c) = t;
  }
}

// Decorrelation (the reduction of [CYZ05]): from the last pair up, make
// column k size-reduced (|L_ik| <= 1/2, i > k) and swap levels k, k+1 when that
// makes the later conditional variance smaller (delta < d_{k+1}); after a swap
// restart from the last pair, re-reducing only the columns up to the swap
// (k_swapped: columns after it are still reduced). Ends with every column
// reduced and d_k + L_{k+1,k}^2 d_{k+1} >= d_{k+1} for every k.
Status LambdaSolver::reduce(LambdaFix& fix) {
  const int n = n_;
  int k = n - 2;
  int k_swapped = n - 2;
  while (k >= 0) {
    if (fix.reduction_steps >= max_reduction_steps_) return kLambdaSearchFailed;
    ++fix.reduction_steps;
    if (k <= k_swapped) {
      for (int i = k + 1; i < n; ++i) integer_gauss(i, k);
    }
    const double l = l_(k + 1, k);
    const double delta = d_(k) + l * l * d_(k + 1);
    if (delta < (1.0 - kSwapMargin) * d_(k + 1)) {
      permute(k, delta);
      ++fix.permutations;
      k_swapped = k;
      k = n - 2;
    } else {
      --k;
    }
  }
  // Z and Z^-1 must stay exact integers in double; L and D finite.
  constexpr double kMaxExactInteger = 4503599627370496.0;  // 2^52
  for (int r = 0; r < n; ++r) {
    if (!std::isfinite(d_(r)) || !(d_(r) > 0.0)) return kLambdaNotPositiveDefinite;
    for (int c = 0; c < n; ++c) {
      if (!std::isfinite(l_(r, c))) return kLambdaNotPositiveDefinite;
      if (!(std::fabs(z_(r, c)) < kMaxExactInteger) || !(std::fabs(z_inv_(r, c)) < kMaxExactInteger)) {
        return kLambdaNotPositiveDefinite;
      }
    }
  }
  return Status::kOk;
}

// First value tried at level k: the nearest integer to the conditional float
// z_bar_k; the next one is on the side of z_bar_k (Schnorr-Euchner, [CYZ05]).
void LambdaSolver::first_value(int k) {
  z_try_(k) = std::round(z_cond_(k));
  step_(k) = z_cond_(k) >= z_try_(k) ? 1.0 : -1.0;
}

// Zig-zag around z_bar_k: z, z+1, z-1, z+2, ... (or mirrored), so the distance
// |z - z_bar_k| never decreases and a level is done at the first value outside.
void LambdaSolver::next_value(int k) {
  z_try_(k) += step_(k);
  step_(k) = -step_(k) - (step_(k) > 0.0 ? 1.0 : -1.0);
}

// Search (MLAMBDA [CYZ05]; [JT96]). With Q_z = L^T D L,
//   (z_hat - z)^T Q_z^-1 (z_hat - z) = sum_k (z_k - z_bar_k)^2 / d_k,
//   z_bar_k = z_hat_k + sum_{i>k} L_ik (z_i - z_bar_i)
// (z_bar_k: the float z_k conditioned on the integers chosen above it).
// Depth first from k = n-1 down to 0; the bound chi^2 is infinite until
// kLambdaCandidates vectors are found, then the largest kept norm, shrunk at
// each better vector that replaces the worst kept one. The norms in z space
// equal those in a space: Z is unimodular (z = Z^T a).
Status LambdaSolver::search(LambdaFix& fix) {
  const int n = n_;
  int found = 0;
  double chi2 = std::numeric_limits<double>::infinity();
  int k = n - 1;
  partial_(n) = 0.0;
  z_cond_(k) = z_hat_(k);
  first_value(k);
  uint32_t steps = 0;
  for (;;) {
    if (steps >= max_search_steps_) {
      fix.search_steps = steps;
      return kLambdaSearchFailed;
    }
    ++steps;
    const double dev = z_try_(k) - z_cond_(k);
    const double norm = partial_(k + 1) + dev * dev / d_(k);
    if (norm < chi2) {
      if (k > 0) {
        // Down one level: conditional float of level k-1 given levels k..n-1.
        partial_(k) = norm;
        --k;
        double cond = z_hat_(k);
        for (int i = k + 1; i < n; ++i) cond += l_(i, k) * (z_try_(i) - z_cond_(i));
        z_cond_(k) = cond;
        first_value(k);
        continue;
      }
      // A full integer vector inside the bound.
      int slot = found;
      if (found == kLambdaCandidates) {
        slot = 0;
        for (int c = 1; c < kLambdaCandidates; ++c) {
          if (cand_norm_[c] > cand_norm_[slot]) slot = c;
        }
      } else {
        ++found;
      }
      cand_[slot] = z_try_;
      cand_norm_[slot] = norm;
      if (found == kLambdaCandidates) {
        chi2 = cand_norm_[0];
        for (int c = 1; c < kLambdaCandidates; ++c) chi2 = std::fmax(chi2, cand_norm_[c]);
      }
      next_value(0);
    } else {
      // Outside the bound: this level is done, next value one level up.
      if (k == n - 1) break;
      ++k;
      next_value(k);
    }
  }
  fix.search_steps = steps;
  return found == kLambdaCandidates ? Status::kOk : kLambdaSearchFailed;
}

}  // namespace uwbnav

#endif  // UWBNAV_LAMBDA
