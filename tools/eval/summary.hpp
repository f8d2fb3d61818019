// The result table the main job and `uwbnav replay` print: accuracy of the
// firmware's solution and of the LS baseline against truth, range and input counts.
#pragma once

#include <cstdio>
#include <string>

#include "tools/dataset/recording.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/eval/replay.hpp"

namespace uwbnav::eval {

struct RunSummary {
  std::string name;
  bool has_truth = false;
  AccuracyStats filter;       // firmware solution (body origin) vs truth
  AccuracyStats ls_uwb;       // LS-UWB baseline (tag antenna) vs tag truth
  AccuracyStats inertial;     // the epochs the IMU filter published (NavMode kInertial)
  AccuracyStats fallback;     // the epochs a fallback published (ranges-only, aligning, recovering)
  uint64_t ranges_used = 0;
  uint64_t ranges_rejected = 0;
  uint64_t ranges_nlos_labelled = 0;   // truth labels (evaluation only)
  AppStats input;                      // validation counters per source and reason
  uint64_t imu_rejected = 0;
  uint64_t uwb_rejected = 0;
  uint64_t cycles = 0;
  double wall_s = 0.0;
  uint32_t resets = 0;
  uint32_t reinits = 0;
};

RunSummary summarise(const dataset::Recording& rec, const ReplayResult& result);

// Human-readable table (Markdown-compatible) on `f`.
void print_summary(std::FILE* f, const RunSummary& s);

}  // namespace uwbnav::eval
