// Evaluation of carrier-phase relative positioning (estimator/rtk_baseline)
// on simulated raw observations (tools/sim/gnss_raw): "BDS only" versus
// "BDS + UWB" over seeded, randomised runs with a street-canyon stretch:
// fix rate and wrong-fix rate in open sky and in the canyon, time to first
// fix, time to re-fix after the canyon, baseline RMSE (issue 16 items 3-5,
// seed 002). The filter never sees the simulator's noise levels: it runs with
// its own defaults (rtk_eval_settings). docs/lambda.md.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "estimator/rtk_baseline.hpp"
#include "tools/sim/gnss_raw.hpp"

namespace uwbnav::eval {

struct RtkRunMetrics {
  int epochs = 0;              // epochs with a valid DD update
  int fixed_epochs = 0;        // ratio >= threshold
  int wrong_fixed_epochs = 0;  // fixed, but an integer != truth
  // Per segment, over all epochs of the segment (refused epochs count as not fixed).
  int open_epochs = 0, open_fixed = 0, open_wrong = 0;
  int canyon_epochs = 0, canyon_fixed = 0, canyon_wrong = 0;
  double ttff_s = -1.0;        // time of the first fixed epoch since the start [s], -1: never fixed
  bool fixed_at_exit = false;  // the last canyon epoch was fixed (the fix held through the canyon's end)
  double refix_s = -1.0;       // not fixed at the exit: first fixed epoch after the canyon, since its end [s]; -1: never / n.a.
  bool has_canyon = false;
  double sq_err_fixed_m2 = 0.0;    // sum of |b_fix - b_true|^2 over fixed epochs
  double sq_err_correct_m2 = 0.0;  // same over the correctly fixed epochs
  double sq_err_float_m2 = 0.0;    // sum of |b_float - b_true|^2 over all valid epochs
};

struct RtkEvalSettings {
  RtkParams params;  // filter parameters: RtkParams defaults, not the simulator's values
  // Baseline random-walk PSD of the filter [m^2/s]: the upper end of the
  // simulated family's walk (rtk_eval_sim_config), a design value.
  double relative_motion_psd_m2_s = 0.05 * 0.05;
};

// Simulator configuration of one evaluation run: noise levels, baseline walk
// and the canyon (start, length, wall height, multipath) drawn from the seed
// (docs/lambda.md lists the ranges). open_sky: no canyon.
sim::GnssRawConfig rtk_eval_sim_config(uint64_t seed, bool open_sky = false);
RtkEvalSettings rtk_eval_settings();

// One run of the filter over a simulated run, with or without the UWB range.
RtkRunMetrics run_rtk_once(const std::vector<sim::GnssRawEpoch>& run, bool use_uwb, const RtkEvalSettings& s);

struct RtkSummary {
  std::string name;
  int runs = 0;
  double fix_rate = 0.0;          // fixed epochs / valid epochs
  double wrong_fix_rate = 0.0;    // wrong fixed epochs / fixed epochs
  double open_fix_rate = 0.0;     // open-sky fixed epochs / open-sky epochs
  double open_wrong_rate = 0.0;   // open-sky wrong fixes / open-sky fixes
  double canyon_fix_rate = 0.0;   // canyon fixed epochs / canyon epochs (NaN without canyon)
  double canyon_wrong_rate = 0.0;
  double ttff_median_s = 0.0;     // over all runs, never-fixed runs counted as +inf (inf if half never fixed)
  double ttff_max_s = 0.0;        // over runs that fixed
  int never_fixed = 0;
  int held_at_exit = 0;           // runs fixed at the canyon's last epoch
  int lost_at_exit = 0;           // runs with a canyon not fixed at its last epoch
  double refix_median_s = 0.0;    // over lost_at_exit runs: time from the canyon's end to a fix, never = +inf
  int never_refixed = 0;          // lost_at_exit runs never fixed again
  double fixed_rmse_m = 0.0;      // 3-D baseline error of the fixed epochs (wrong fixes included)
  double correct_rmse_m = 0.0;    // 3-D baseline error of the correctly fixed epochs
  double float_rmse_m = 0.0;      // 3-D baseline error of the float solution, all valid epochs
};
RtkSummary summarise_rtk(const std::string& name, const std::vector<RtkRunMetrics>& runs);

void print_rtk_table(std::FILE* f, const std::vector<RtkSummary>& rows, bool markdown);

// CLI: uwbnav eval rtk [--seeds tuning|reporting|N-M] [--runs N] [--slip-rate HZ] [--open-sky] [--markdown]
int run_eval_rtk(int argc, char** argv);

}  // namespace uwbnav::eval
