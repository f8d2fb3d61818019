// LAMBDA integer least-squares ambiguity resolution (Teunissen 1995; de Jonge &
// Tiberius 1996; search of MLAMBDA, Chang, Yang & Zhou 2005): float carrier-phase
// ambiguities [cycles] and their covariance in, the two best integer vectors,
// their squared residual norms and the ratio test out. Double precision, static
// memory (work matrices are members of LambdaSolver). docs/lambda.md.
//
// References:
//  [T95]  P.J.G. Teunissen, "The least-squares ambiguity decorrelation
//         adjustment: a method for fast GPS integer ambiguity estimation",
//         J. Geodesy 70:65-82, 1995.
//  [JT96] P. de Jonge, C. Tiberius, "The LAMBDA method for integer ambiguity
//         estimation: implementation aspects", LGR-Series No. 12, Delft
//         Geodetic Computing Centre, 1996.
//  [CYZ05] X.-W. Chang, X. Yang, T. Zhou, "MLAMBDA: a modified LAMBDA method
//         for integer least-squares estimation", J. Geodesy 79:552-565, 2005.
#pragma once

// Compiled in by default; boards that do not need carrier-phase ambiguity
// resolution and are short of flash build without it (hal/mps2: UWBNAV_LAMBDA=0,
// issue 16 item 3 is not required on the Cortex-M4F).
#ifndef UWBNAV_LAMBDA
#define UWBNAV_LAMBDA 1
#endif

#if UWBNAV_LAMBDA

#include <Eigen/Core>
#include <cstdint>

#include "estimator/status.hpp"

namespace uwbnav {

// Largest number of ambiguities per problem (double differences of two
// frequencies to 8 satellites). Work matrices are kLambdaMaxAmb^2 doubles each.
constexpr int kLambdaMaxAmb = 16;
// Integer candidates kept by the search: the best and the second best (ratio test).
constexpr int kLambdaCandidates = 2;
static_assert(kLambdaCandidates == 2, "LambdaFix and the ratio test hold a best and a second best");
// Ratio-test threshold second/best from which the best is accepted (seed 002: fixed when RATIO > 3).
constexpr double kLambdaDefaultRatio = 3.0;
// Ratio reported when the best candidate's squared norm is 0 (float solution on
// an integer vector) or the ratio would exceed it: the best is unique beyond
// doubt, so the ratio is large and finite rather than undefined. RTKLIB
// (rtkpos.c) displays 0 in that case but accepts the fix, as here; its test
// is s[0] <= 0 || s[1]/s[0] >= threshold, the same ">=" as LambdaFix::fixed.
constexpr double kLambdaMaxRatio = 1e9;
// Iteration caps (defaults of LambdaSolver::set_step_caps). Reduction: passes
// of the decorrelation loop (each one column of integer Gauss transformations
// and at most one permutation, after which the loop restarts at the last
// pair); it terminates in exact arithmetic, the cap guards against rounding
// cycling. Search: nodes visited by the depth-first enumeration (one integer
// tried at one level per step). Worst seen (docs/lambda.md "Cost"), n = 16,
// 5000 random Q per condition number: 4896 passes / 1264 steps at 1e6, 8237 /
// 1518 at 1e10; GNSS-like dual-frequency Q: 1469 / 173. The caps are 24x and
// 65x above the worst seen: about 4 ms and 2.5 ms on the development host
// (~19 ns per pass, ~25 ns per step at n = 16).
constexpr uint32_t kLambdaMaxReductionSteps = 200000;
constexpr uint32_t kLambdaMaxSearchSteps = 100000;
// A conditional variance below this share of the ambiguity's own variance is
// numerically singular: double carries ~1e-16 relative error, so the pivot
// would have fewer than four correct digits.
constexpr double kLambdaMinPivotRatio = 1e-12;
// Float ambiguities must be exactly roundable in double (|a| < 2^52 cycles).
constexpr double kLambdaMaxAbsAmb_cyc = 4503599627370496.0;

// Statuses of LambdaSolver::solve beyond kOk (codes of estimator/status.hpp).
//  kInvalidArgument: n = 0 or n > kLambdaMaxAmb, a non-finite ambiguity or
//    covariance entry, |a| >= kLambdaMaxAbsAmb_cyc, threshold < 1 or not finite.
//  kLambdaNotPositiveDefinite: Q not (numerically) positive definite.
//  kLambdaSearchFailed: reduction or search exceeded its iteration cap.
constexpr Status kLambdaNotPositiveDefinite = Status::kSingular;
constexpr Status kLambdaSearchFailed = Status::kNotFound;

// Fixed-size storage; only the leading n (x n) entries are used. Always double,
// also in the float estimator build: ambiguity covariances are ill-conditioned
// (the two frequencies of one satellite are correlated to within 1e-5 of 1;
// RTKLIB's dual-frequency test Q: 1 - 3.2e-6, condition number 2.3e6), float's
// 6e-8 relative precision would leave no correct digit in the conditional
// variances and lose the integer structure.
using LambdaMat = Eigen::Matrix<double, kLambdaMaxAmb, kLambdaMaxAmb>;
using LambdaVec = Eigen::Matrix<double, kLambdaMaxAmb, 1>;

// Result of one solve. Integer vectors are held as integer-valued doubles.
struct LambdaFix {
  int n = 0;                                   // ambiguities in use
  LambdaVec best_cyc = LambdaVec::Zero();      // best integer vector a_1 [cycles]
  LambdaVec second_cyc = LambdaVec::Zero();    // second best a_2 [cycles]
  double best_sq_norm = 0.0;                   // (a_hat - a_1)^T Q^-1 (a_hat - a_1) [-]
  double second_sq_norm = 0.0;                 // same for a_2 [-]
  double ratio = 0.0;                          // second_sq_norm / best_sq_norm [-] (kLambdaMaxRatio when best is 0)
  bool fixed = false;                          // ratio >= the threshold: accept best_cyc
  uint32_t reduction_steps = 0;                // passes of the decorrelation loop
  uint32_t permutations = 0;                   // of which permuted a pair
  uint32_t search_steps = 0;                   // nodes visited by the search
};

class LambdaSolver {
 public:
  LambdaSolver();

  // Integer least squares: the two integer vectors a minimising
  //   (a_hat - a)^T Q^-1 (a_hat - a)                                  [T95]
  // for float ambiguities a_hat [cycles] (float_amb_cyc, first n entries) and
  // their covariance Q [cycles^2] (cov_cyc2, leading n x n block; only the
  // lower triangle i >= j is read: Q is symmetric by definition), and the
  // ratio test against ratio_threshold (>= 1). On any status but kOk, `fix`
  // is reset (n = 0, fixed = false) except the step counters (how far the
  // reduction and the search got).
  [[nodiscard]] Status solve(const LambdaVec& float_amb_cyc, const LambdaMat& cov_cyc2, int n, LambdaFix& fix,
                             double ratio_threshold = kLambdaDefaultRatio);

  // Iteration caps of reduce and search (kLambdaMaxReductionSteps,
  // kLambdaMaxSearchSteps by default; 0 keeps the default). Exceeding one
  // makes solve() return kLambdaSearchFailed.
  void set_step_caps(uint32_t max_reduction_steps, uint32_t max_search_steps);

  // State of the last successful solve (leading n x n / n entries), for tests
  // and diagnostics:
  //  transform(): the unimodular Z, decorrelated z = Z^T a, Q_z = Z^T Q Z;
  //  transform_inverse(): Z^-1 (integer as well), a = Z^-T z;
  //  factor_l(), factor_d(): Q_z = L^T D L, L unit lower triangular;
  //  decorrelated_float(): z_hat = Z^T (a_hat - round(a_hat)) [cycles].
  int size() const { return n_; }
  const LambdaMat& transform() const { return z_; }
  const LambdaMat& transform_inverse() const { return z_inv_; }
  const LambdaMat& factor_l() const { return l_; }
  const LambdaVec& factor_d() const { return d_; }
  const LambdaVec& decorrelated_float() const { return z_hat_; }

 private:
  Status factorise(const LambdaMat& cov_cyc2);
  Status reduce(LambdaFix& fix);
  Status search(LambdaFix& fix);
  void integer_gauss(int i, int j);
  void permute(int k, double delta);
  void first_value(int k);
  void next_value(int k);

  int n_ = 0;
  uint32_t max_reduction_steps_ = kLambdaMaxReductionSteps;
  uint32_t max_search_steps_ = kLambdaMaxSearchSteps;
  LambdaMat l_;      // L of Q = L^T D L, then of Q_z after the reduction
  LambdaVec d_;      // D (conditional variances) [cycles^2]
  LambdaMat z_;      // Z, integer entries
  LambdaMat z_inv_;  // Z^-1, integer entries
  LambdaVec a_round_;  // round(a_hat) [cycles]
  LambdaVec z_hat_;    // Z^T (a_hat - round(a_hat)) [cycles]
  // Search scratch, one entry per level k (the search runs k = n-1 .. 0).
  LambdaVec z_try_;    // integer value tried at level k
  LambdaVec z_cond_;   // conditional float value z_bar_k given the levels above
  LambdaVec step_;     // next zig-zag step at level k (+-1, -+2, +-3, ...)
  Eigen::Matrix<double, kLambdaMaxAmb + 1, 1> partial_;  // squared norm of the levels above k
  LambdaVec cand_[kLambdaCandidates];  // candidates in z space
  double cand_norm_[kLambdaCandidates] = {};
};

}  // namespace uwbnav

#endif  // UWBNAV_LAMBDA
