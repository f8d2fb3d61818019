// `uwbnav eval family`: the firmware over the randomized scenario family (or
// the real recordings), accuracy together with its honesty per family cell
// (docs/evaluation.md "Scenario family").
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "estimator/navigator.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/eval/eval_nlos.hpp"
#include "tools/eval/replay.hpp"

namespace uwbnav::eval {

// Recoveries of the estimator by kind. One place that reads them from the
// diagnostics, so new kinds of recovery are counted everywhere at once.
struct RecoveryCounts {
  uint64_t resets = 0;      // hard resets (non-finite or exploded state)
  uint64_t reinits = 0;     // re-alignments of the IMU filter (ranges-only output meanwhile)
  uint64_t inflations = 0;  // divergence met by covariance inflation
  uint64_t reanchors = 0;   // divergence met by re-anchoring to the ranges
};
RecoveryCounts count_reinits(const NavDiagnostics& diag);

// Figures of one drive, as sums so that cells pool them exactly.
struct DriveMetrics {
  std::string name;             // family:CELL:SEED or the recording's name
  bool ok = false;              // replay ran
  std::string error;
  double hours = 0.0;           // span of the outputs [h]
  // Accuracy (good epochs with truth; good = status valid/degraded with a finite position).
  size_t err_n = 0;
  double err_sq_sum = 0.0;      // sum of squared horizontal errors [m^2]
  double rmse_h_m = 0.0;        // NaN without a good epoch
  double max_h_m = 0.0;
  double p95_h_m = 0.0;
  // Availability.
  size_t epochs = 0;            // output epochs from the first good one on
  size_t good = 0;              // of which good
  double longest_gap_s = 0.0;   // longest stretch without a good epoch after the first [s]
  double ttfe_s = 0.0;          // first good epoch minus first range [s]; NaN when none
  // Honesty (good epochs with truth and a finite claimed sigma).
  size_t hon_n = 0;
  size_t in2s_h = 0, in2s_x = 0, in2s_y = 0;
  size_t nees_n = 0, nees_in = 0;  // 2-D NEES; in = NEES <= 5.991
  double nees_sum = 0.0;
  size_t nis_n = 0, nis_in = 0;    // NIS of used ranges; in = NIS <= 3.841
  double nis_sum = 0.0;
  RecoveryCounts recoveries;
  // Fallback: good epochs with truth whose mode is not the inertial filter.
  size_t fallback_n = 0;
  double fallback_sq_sum = 0.0;
  size_t fallback_hon_n = 0, fallback_in2s_h = 0;  // of hon_n / in2s_h, the fallback's share
  // Sparse anchors: good epochs with truth inside a stretch of >= 20 s in which
  // fewer than 3 distinct anchors (vehicle ids excluded) were heard in the 2 s
  // before each epoch (issue 16's "sees < 3 anchors for >= 20 s"; computed from
  // the recording, never shown to the firmware).
  size_t sparse_n = 0, sparse_in2s_xy = 0;  // in2s: x and y axes counted separately
  double sparse_sq_sum = 0.0, sparse_max_m = 0.0;
  uint64_t ranges_used = 0, ranges_rejected = 0;
  uint64_t los_ranges = 0, los_fused = 0;  // ranges the recording labels LOS, and those of them fused
  Confusion nlos;               // decisions vs labels (labels never reach the firmware)
  double wall_s = 0.0;          // simulation + replay wall time [s]
};

// Evaluates one replay against the recording's truth and labels.
DriveMetrics drive_metrics(const dataset::Recording& rec, const ReplayResult& res);

// Pooled figures of a group of drives (a cell, the real set, or all).
struct CellSummary {
  std::string name;
  size_t drives = 0, failed = 0;
  double hours = 0.0;
  double rmse_med = 0.0, rmse_worst = 0.0;
  double max_med = 0.0, max_worst = 0.0;
  double p95_med = 0.0;
  double availability = 0.0;
  double gap_max_s = 0.0;
  double ttfe_med_s = 0.0, ttfe_max_s = 0.0;
  double in2s_h = 0.0, in2s_x = 0.0, in2s_y = 0.0;
  double nees_mean = 0.0, nees_in = 0.0;
  double nis_mean = 0.0, nis_in = 0.0;
  double resets_per_h = 0.0, reinits_per_h = 0.0;  // per hour of drive
  double inflations_per_h = 0.0, reanchors_per_h = 0.0;
  double fallback_share = 0.0, fallback_rmse = 0.0;
  double inertial_rmse = 0.0;  // pooled horizontal RMSE of the epochs published by the IMU filter [m]
  double fallback_in2s_h = 0.0, inertial_in2s_h = 0.0;  // "in 2sig h" of each mode's epochs
  double fused_share = 0.0;      // fused / (fused + rejected by gating), all ranges
  double los_fused_share = 0.0;  // fused share of the LOS-labelled ranges (validation drops count as not fused)
  double nlos_false_alarm = 0.0; // LOS-labelled ranges the gating called NLOS: FP / (FP + TN)
  double sparse_share = 0.0, sparse_rmse = 0.0, sparse_max = 0.0, sparse_in2s = 0.0;  // epochs with < 3 anchors heard
  double nlos_precision = 0.0, nlos_recall = 0.0;
};
CellSummary summarise_cell(const std::string& name, const std::vector<DriveMetrics>& drives);

// Seeds of `--seeds`: "tuning" (1-99), "reporting" (1000-1999), "N-M" or "N".
bool parse_seed_set(const std::string& text, uint64_t& first, uint64_t& last);

// Real recordings: <repo>/data first, then <repo>/../shared/data.
std::string find_real_data_dir();

// Format v1 recordings (directories with uwb.csv or uwb.csv.gz) under `root`, two levels deep, sorted.
std::vector<std::string> find_recordings(const std::string& root);

// Prints the two tables (accuracy/availability, honesty/robustness), Markdown or aligned text.
void print_family_tables(std::FILE* f, const std::vector<CellSummary>& rows, bool markdown);

// CLI: uwbnav eval family [--cells a,b] [--seeds tuning|reporting|N-M] [--drives-per-cell K]
//      [--param name=value]... [--fast] [--markdown] [--verbose] [--jobs N] [--real] [--data DIR]
int run_eval_family(int argc, char** argv);

}  // namespace uwbnav::eval
