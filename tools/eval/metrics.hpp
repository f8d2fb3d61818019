// Accuracy metrics against truth (seed 000 eq. 14-16): horizontal RMSE, MAX,
// STD, per-axis error percentiles, and the share of errors inside the claimed 2-sigma.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "tools/dataset/recording.hpp"

namespace uwbnav::eval {

// One estimate compared with interpolated truth (body origin).
struct ErrorSample {
  uint64_t t_us = 0;
  double err_nav_m[3] = {0, 0, 0};    // estimate - truth [m]
  double sigma_nav_m[3] = {0, 0, 0};  // claimed 1-sigma [m] (NaN when unknown)
  int status = 0;
};

struct AccuracyStats {
  size_t epochs = 0;            // epochs with a solution and truth
  size_t epochs_total = 0;      // all epochs within the truth span
  double rmse_h_m = 0.0;        // horizontal RMSE (eq. 14)
  double max_h_m = 0.0;         // horizontal MAX (eq. 15)
  double std_h_m = 0.0;         // STD of the horizontal error magnitude (eq. 16)
  double mean_h_m = 0.0;
  double p50_east_m = 0.0, p70_east_m = 0.0, p90_east_m = 0.0;     // |x error| percentiles (Table 4)
  double p50_north_m = 0.0, p70_north_m = 0.0, p90_north_m = 0.0;  // |y error| percentiles
  double inside_2sigma_x = 0.0;  // fraction of |ex| <= 2 sx
  double inside_2sigma_y = 0.0;
};

// Linear interpolation of truth position at t_us. False outside the truth span
// or across a gap longer than max_gap_us.
bool truth_at(const std::vector<dataset::TruthRow>& truth, uint64_t t_us, double pos_nav_m[3],
              uint64_t max_gap_us = 200000);

// Errors of the estimates with status valid or degraded against truth.
std::vector<ErrorSample> compare_with_truth(const std::vector<dataset::EstimateRow>& est,
                                            const std::vector<dataset::TruthRow>& truth);

AccuracyStats accuracy(const std::vector<ErrorSample>& errors, size_t epochs_total);

// q-quantile (0..1) of values (copied and partially sorted).
double quantile(std::vector<double> values, double q);

}  // namespace uwbnav::eval
