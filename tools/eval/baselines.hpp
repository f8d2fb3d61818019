// Reference solutions the filter is compared with (seed 000 Table 3 rows):
// LS-UWB (linear least squares on the epoch's latest ranges) and LS-Taylor
// (Gauss-Newton on the same ranges, seed 003 eq. 1-4), per 10 ms epoch;
// computed on the fly from ranges fed in time order (LsBaseline) or over a
// whole recording in memory.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "tools/dataset/recording.hpp"
#include "tools/eval/metrics.hpp"

namespace uwbnav::eval {

enum class LsMethod { kLinear, kTaylor };

// The LS baseline fed one range at a time, in time order, in constant memory:
// the latest range per anchor and the epoch clock. Every epoch with a fix is
// handed to `on_fix` as soon as all ranges up to its time have been added.
class LsBaseline {
 public:
  using FixFn = std::function<void(const dataset::EstimateRow&)>;
  LsBaseline(const SiteConfig& site, LsMethod method, FixFn on_fix, uint64_t window_us = 150000);
  // A range of the recording (any tag, any anchor), not earlier than the last one added.
  void add(const UwbRange& r);
  // Solves the epochs up to `t_us`; every range with time <= t_us must have been added.
  void advance_to(uint64_t t_us);
  // Solves the remaining epochs, up to one period after the last range.
  void finish();

 private:
  void solve(uint64_t t_us);

  const SiteConfig& site_;
  LsMethod method_;
  FixFn on_fix_;
  uint64_t window_us_;
  uint8_t tag_ = 0;
  bool two_d_ = false;
  float tag_z_m_ = 0.0F;
  uint64_t last_t_us_[kMaxAnchors] = {};
  float last_range_m_[kMaxAnchors] = {};
  bool have_[kMaxAnchors] = {};
  bool started_ = false;
  uint64_t next_epoch_us_ = 0;  // the first epoch not yet solved
  uint64_t t_last_range_us_ = 0;
  bool have_prev_ = false;
  Vec3f prev_nav_m_{};
};

// Solves the tag position at every 10 ms epoch from the latest range of each
// anchor (tag 0 / first tag) received in the previous `window_us`. Uses 2-D
// mode with the tag's surveyed height when the anchors are near-planar.
// Returns one row per epoch with a fix; status 1, sigma from the LS covariance.
std::vector<dataset::EstimateRow> ls_baseline(const dataset::Recording& rec, LsMethod method,
                                              uint64_t window_us = 150000);

// Truth of the first tag's antenna (truth position + R * lever when truth has
// attitude; otherwise the body origin raised by the lever's z).
std::vector<dataset::TruthRow> tag_truth(const dataset::Recording& rec);
// The same for one truth row.
dataset::TruthRow tag_truth_row(const SiteConfig& site, const dataset::TruthRow& body);

}  // namespace uwbnav::eval
