// Standard normal and chi-square upper-tail quantiles for the RAIM thresholds of
// seed 001 (global test: chi-square with n - unknowns degrees of freedom at a
// false-alarm probability; local test: standard normal), in single precision.
// The API takes upper-tail probabilities: the thresholds are driven by small
// false-alarm probabilities, and 1 - p_fa in float would lose them (1 - 1e-9F
// is 1). No heap, no double, bounded iterations; meant to be evaluated when
// parameters change, not per range.
#pragma once

namespace uwbnav {

constexpr int kChiSquareMaxDof = 64;

// Upper-tail quantile of N(0,1): x with 1 - Phi(x) = q, q in [FLT_MIN, 1)
// (normal floats); NaN outside.
// Wichura's AS 241 PPND7 rational approximation (relative error ~1e-7),
// evaluated on the tail q itself (no 1 - q for q < 0.5).
float normal_upper_quantile(float q);

// Upper tail of the chi-square distribution with dof degrees of freedom
// (1..kChiSquareMaxDof): regularised upper incomplete gamma Q(dof/2, x/2).
// 1 for x <= 0; NaN for an invalid dof or NaN x.
float chi_square_upper_tail(float x, int dof);

// CDF of the same distribution: P(dof/2, x/2) = 1 - Q(dof/2, x/2), each side
// computed directly where it is small.
float chi_square_cdf(float x, int dof);

// Upper-tail quantile: x with chi_square_upper_tail(x, dof) = q, q in
// [2 FLT_MIN, 1), dof 1..kChiSquareMaxDof; NaN outside. dof 1 and 2 in closed
// form (normal quantile of q/2, squared; -2 ln q), otherwise Wilson-Hilferty
// start and Newton steps on ln Q (ln P for q > 1/2).
float chi_square_upper_quantile(float q, int dof);

}  // namespace uwbnav
