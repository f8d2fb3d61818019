// `uwbnav eval report`: runs every positioning method over recordings and
// writes the seed-000-style tables (Markdown + CSV), the series the figures
// are drawn from, and the figures (PNG, drawn by tools/plot/report_plots.py).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/dataset/recording.hpp"
#include "tools/eval/eval_nlos.hpp"
#include "tools/eval/metrics.hpp"

namespace uwbnav::eval {

struct MethodResult {
  std::string name;          // row label
  std::string key;           // file-name friendly id
  AccuracyStats acc;
  bool has_nlos = false;     // the method makes per-range NLOS decisions
  Confusion nlos;            // NLOS decisions vs labels (seed 000 eq. 11-13)
  double us_per_cycle = 0.0; // host wall time per 10 ms cycle [us]
  uint64_t ranges_used = 0, ranges_rejected = 0;
  std::vector<ErrorSample> errors;              // for the series / figures
  std::vector<dataset::EstimateRow> estimates;  // positions for the trajectory figure
};

struct RecordingReport {
  std::string name;
  std::string source;        // directory or sim:PRESET:SEED
  size_t imu_samples = 0, ranges = 0, nlos_labelled = 0;
  double duration_s = 0.0;
  std::vector<MethodResult> methods;
};

// Loads "sim:PRESET[:SEED]" (simulated) or a format v1 directory.
[[nodiscard]] Status load_recording_spec(const std::string& spec, dataset::Recording& rec, std::string* error);

// Runs all methods over one recording.
RecordingReport evaluate_recording(const dataset::Recording& rec, const std::string& source);

// Writes tables, series and (if python3+matplotlib are present) figures to dir.
[[nodiscard]] Status write_recording_report(const RecordingReport& r, const std::string& dir, bool figures);

// CLI: uwbnav eval report RECORDING... --out DIR [--jobs N] [--no-figures]
int run_eval_report(int argc, char** argv);

}  // namespace uwbnav::eval
