// Reference solutions the filter is compared with (seed 000 Table 3 rows):
// LS-UWB (linear least squares on the epoch's latest ranges) and LS-Taylor
// (Gauss-Newton on the same ranges, seed 003 eq. 1-4), per 10 ms epoch.
#pragma once

#include <vector>

#include "tools/dataset/recording.hpp"
#include "tools/eval/metrics.hpp"

namespace uwbnav::eval {

enum class LsMethod { kLinear, kTaylor };

// Solves the tag position at every 10 ms epoch from the latest range of each
// anchor (tag 0 / first tag) received in the previous `window_us`. Uses 2-D
// mode with the tag's surveyed height when the anchors are near-planar.
// Returns one row per epoch with a fix; status 1, sigma from the LS covariance.
std::vector<dataset::EstimateRow> ls_baseline(const dataset::Recording& rec, LsMethod method,
                                              uint64_t window_us = 150000);

// Truth of the first tag's antenna (truth position + R * lever when truth has
// attitude; otherwise the body origin raised by the lever's z).
std::vector<dataset::TruthRow> tag_truth(const dataset::Recording& rec);

}  // namespace uwbnav::eval
