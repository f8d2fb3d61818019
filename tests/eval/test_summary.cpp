// The result table of `uwbnav run` / `replay`: the filter's figures split by
// the mode that published each epoch, so that a fallback phase (start,
// alignment, recovery) is never hidden inside one average.
#include <gtest/gtest.h>

#include <cmath>

#include "tools/eval/summary.hpp"

namespace uwbnav::eval {
namespace {

dataset::EstimateRow at(uint64_t t_us, double x, NavMode mode) {
  dataset::EstimateRow e;
  e.t_us = t_us;
  e.pos_nav_m[0] = x;
  e.pos_sigma_m[0] = e.pos_sigma_m[1] = e.pos_sigma_m[2] = 1.0;
  e.status = 1;
  e.mode = static_cast<int>(mode);
  return e;
}

TEST(RunSummary, FilterFiguresAreSplitIntoImuFilterAndFallbackEpochs) {
  // GIVEN truth at the origin for 10 s and four published epochs: two from the
  // ranges-only fallback 2 m off, two from the IMU filter 0.1 m off, one before any fix
  dataset::Recording rec;
  for (uint64_t t = 0; t <= 10000000; t += 10000) {
    dataset::TruthRow r;
    r.t_us = t;
    rec.truth.push_back(r);
  }
  ReplayResult res;
  dataset::EstimateRow none = at(500000, 0.0, NavMode::kNone);
  none.status = 0;
  none.pos_nav_m[0] = std::nan("");
  res.estimates.push_back(none);
  res.estimates.push_back(at(1000000, 2.0, NavMode::kAligning));
  res.estimates.push_back(at(1010000, 2.0, NavMode::kRecovering));
  res.estimates.push_back(at(2000000, 0.1, NavMode::kInertial));
  res.estimates.push_back(at(2010000, 0.1, NavMode::kInertial));
  // WHEN summarised
  const RunSummary s = summarise(rec, res);
  // THEN the whole and each part carry their own epochs and errors
  EXPECT_EQ(s.filter.epochs, 4U);
  EXPECT_EQ(s.fallback.epochs, 2U);
  EXPECT_EQ(s.inertial.epochs, 2U);
  EXPECT_NEAR(s.fallback.rmse_h_m, 2.0, 1e-9);
  EXPECT_NEAR(s.inertial.rmse_h_m, 0.1, 1e-9);
  EXPECT_NEAR(s.filter.rmse_h_m, std::sqrt((4.0 + 4.0 + 0.01 + 0.01) / 4.0), 1e-9);
}

}  // namespace
}  // namespace uwbnav::eval
