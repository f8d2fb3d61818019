// The result table the main job and `uwbnav replay` print: accuracy of the
// firmware's solution and of the LS baseline against truth, range and input
// counts. Computed on the fly (SummaryBuilder: the replay's epochs, the
// recording's ranges and truth pulled as time advances, constant memory) or
// over a whole replay result in memory (summarise, built on the same).
#pragma once

#include <cstdio>
#include <string>

#include "tools/dataset/recording.hpp"
#include "tools/dataset/recording_stream.hpp"
#include "tools/eval/baselines.hpp"
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

// Builds a RunSummary while a replay runs: receives the firmware's epochs
// (ReplaySink) and pulls the recording's ranges (for the LS baseline and the
// NLOS label count) and truth as far as each epoch's time. `uwb` is a feed of
// the recording's uwb rows of its own (not the one the firmware reads); `truth`
// may be null (no truth: accuracy not computed). All must outlive the builder.
class SummaryBuilder final : public ReplaySink {
 public:
  SummaryBuilder(const SiteConfig& site, std::string name, dataset::RowFeed<dataset::UwbRow>& uwb,
                 dataset::RowFeed<dataset::TruthRow>* truth);
  SummaryBuilder(const SummaryBuilder&) = delete;
  SummaryBuilder& operator=(const SummaryBuilder&) = delete;

  void on_estimate(const dataset::EstimateRow& e) override;
  // Reads the remaining ranges, closes the LS baseline and fills the counters from `result`.
  RunSummary finish(const ReplayResult& result);

 private:
  void take_ranges_up_to(uint64_t t_us);
  void on_ls_fix(const dataset::EstimateRow& fix);

  const SiteConfig& site_;
  std::string name_;
  dataset::RowFeed<dataset::UwbRow>& uwb_;
  bool has_truth_;
  TruthCursor truth_;
  LsBaseline ls_;
  AccuracyAccumulator filter_, inertial_, fallback_, ls_acc_;
  size_t epochs_in_truth_ = 0;
  uint64_t nlos_labelled_ = 0;
};

// The same over a whole replay kept in memory (result.estimates).
RunSummary summarise(const dataset::Recording& rec, const ReplayResult& result);

// Human-readable table (Markdown-compatible) on `f`.
void print_summary(std::FILE* f, const RunSummary& s);

}  // namespace uwbnav::eval
