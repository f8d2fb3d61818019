// Accuracy metrics against truth (seed 000 eq. 14-16): horizontal RMSE, MAX,
// STD, per-axis error percentiles, and the share of errors inside the claimed
// 2-sigma; whole-vector functions and their streaming counterparts (a truth
// cursor and a fixed-size accumulator) for evaluation on the fly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "tools/dataset/recording.hpp"
#include "tools/dataset/recording_stream.hpp"

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

// Truth at increasing times from rows pulled one by one out of a feed: the
// same answers as truth_at() over the whole table, holding two rows.
class TruthCursor {
 public:
  // `feed` null: no truth (every query false).
  explicit TruthCursor(dataset::RowFeed<dataset::TruthRow>* feed, uint64_t max_gap_us = 200000)
      : feed_(feed), max_gap_us_(max_gap_us) {}
  // The truth rows bracketing `t_us`: `before` the last row earlier than t_us
  // (null when none or when `at` is exact), `at` the first row at or after it.
  // False where truth_at() is false. Calls must come with non-decreasing t_us.
  bool bracket(uint64_t t_us, const dataset::TruthRow*& before, const dataset::TruthRow*& at);
  // truth_at() for the body origin.
  bool position(uint64_t t_us, double pos_nav_m[3]);

 private:
  dataset::RowFeed<dataset::TruthRow>* feed_;
  uint64_t max_gap_us_;
  dataset::TruthRow prev_{};
  bool have_prev_ = false;
};

// Linear interpolation between two truth positions at t_us (a.t_us < t_us < b.t_us).
void interpolate(const dataset::TruthRow& a, const dataset::TruthRow& b, uint64_t t_us, double pos_nav_m[3]);

// AccuracyStats of errors fed one at a time, in constant memory. Percentiles
// are not kept (NaN in stats()); every other field as accuracy().
class AccuracyAccumulator {
 public:
  void add(const ErrorSample& e);
  AccuracyStats stats(size_t epochs_total) const;
  size_t epochs() const { return n_; }

 private:
  size_t n_ = 0;
  double sum_h2_ = 0.0;   // sum of squared horizontal errors [m^2]
  double mean_h_m_ = 0.0; // running mean of the horizontal error (Welford)
  double m2_h_ = 0.0;     // running sum of squared deviations from the mean [m^2]
  double max_h_m_ = 0.0;
  size_t in_x_ = 0, in_y_ = 0, with_sigma_ = 0;
};

}  // namespace uwbnav::eval
