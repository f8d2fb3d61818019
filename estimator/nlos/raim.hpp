// Receiver autonomous integrity monitoring over one epoch of ranges (seed 001):
// LS-Taylor fix (estimator/ls_taylor.hpp), chi-square global test on the
// weighted residuals with dof = n - unknowns, standardised-residual local test
// (standard normal) to locate the faulty range, exclude it, repeat while
// redundancy remains. Static memory; at most n LS solves per call.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/ls_taylor.hpp"
#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav {

constexpr size_t kRaimMaxRanges = kMaxAnchors;  // one range per anchor in an epoch

// Thresholds derived from the false-alarm probabilities (computed when
// parameters change, chi_square.hpp).
struct RaimThresholds {
  float chi2_by_dof[kRaimMaxRanges + 1] = {};  // global test threshold per dof (index = dof)
  float local = 0.0F;                          // standardised-residual threshold [-]
};

// Global test at false-alarm probability p_fa (chi-square, upper tail) and
// local test at p_fa_local (two-sided normal, Bonferroni over n is not applied).
// Float, in terms of the tail probabilities themselves (no 1 - p_fa), so the
// smallest allowed p_fa (1e-9) keeps its meaning.
void raim_compute_thresholds(float p_fa, float p_fa_local, RaimThresholds& out);

struct RaimResult {
  bool excluded[kRaimMaxRanges] = {};  // range i excluded as faulty
  float std_residual[kRaimMaxRanges] = {};  // last standardised residual per range [-]
  uint8_t num_excluded = 0;
  bool available = false;   // at least one global test could run (dof >= 1)
  bool consistent = false;  // final set passes the global test
  float test_statistic = 0.0F;  // final weighted SSR [-]
  float threshold = 0.0F;       // its chi-square threshold [-]
  LsFix fix;                    // final fix (valid when available)
};

// Runs seed 001 RAIM on n ranges (n <= kRaimMaxRanges). `options` select the
// LS mode (2-D with known height for ground vehicles) and the start point.
// kInvalidArgument when n is too large or inputs are not finite; a too small n
// or a failed LS solve is not an error: available stays false.
[[nodiscard]] Status raim_run(const LsRange* ranges, size_t n, const LsOptions& options,
                              const RaimThresholds& thresholds, RaimResult& out);

}  // namespace uwbnav
