// Standard normal and chi-square quantiles for the RAIM thresholds of seed 001
// (global test: chi-square with n - unknowns degrees of freedom at a false-alarm
// probability; local test: standard normal). No heap, bounded iterations;
// meant to be evaluated when parameters change, not per range.
#pragma once

namespace uwbnav {

constexpr int kChiSquareMaxDof = 64;

// Inverse CDF of N(0,1): x with Phi(x) = p, p in (0,1). NaN outside.
// Acklam's rational approximation refined by one Halley step (|error| < 1e-12).
double normal_quantile(double p);

// CDF of the chi-square distribution with dof degrees of freedom (1..kChiSquareMaxDof):
// regularised lower incomplete gamma P(dof/2, x/2). NaN for invalid input.
double chi_square_cdf(double x, int dof);

// Inverse CDF: x with chi_square_cdf(x, dof) = p, p in (0,1), dof 1..kChiSquareMaxDof.
// Exact closed forms for dof 1 and 2; Wilson-Hilferty start and Newton steps otherwise.
double chi_square_quantile(double p, int dof);

}  // namespace uwbnav
