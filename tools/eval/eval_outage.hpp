// `uwbnav eval outage`: position error during each simulated UWB outage with
// and without the RBF bridging network (ekf.rbf_bridge), in seed 004's form
// (x/y RMSE and maximum per outage length, improvement), with the filter's
// claimed sigma during the outage and the share of epochs inside its 2 sigma.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tools/dataset/recording.hpp"

namespace uwbnav::eval {

// One outage [start, end) of a recording, from its meta.ini `sim_outages_s`.
struct OutageSpan {
  double start_s = 0.0;
  double end_s = 0.0;
};
// Parses "[40,45) [80,90)"; false on a malformed list.
bool parse_outage_list(const std::string& text, std::vector<OutageSpan>& out);

// Error sums over the epochs of a group of outages (pooled exactly).
struct OutageErrors {
  size_t outages = 0;
  size_t n = 0;                 // epochs with a position and truth
  double sq_x = 0.0, sq_y = 0.0;      // sums of squared errors [m^2]
  double max_x = 0.0, max_y = 0.0;    // largest absolute errors [m]
  double max_h = 0.0;                 // largest horizontal error [m]
  double var_x = 0.0, var_y = 0.0;    // sums of claimed variances [m^2]
  size_t in2s_x = 0, in2s_y = 0;      // |e| <= 2 sigma per axis
  size_t in2s_h = 0;                  // horizontal: h <= 2 sqrt(sx^2 + sy^2)
  void add(const OutageErrors& o);
};

// Adds the epochs of `est` inside `span` to `acc` (one outage).
void outage_errors(const std::vector<dataset::EstimateRow>& est, const std::vector<dataset::TruthRow>& truth,
                   const OutageSpan& span, OutageErrors& acc);

// CLI: uwbnav eval outage [--seeds tuning|reporting|N-M] [--drives K] [--param name=value]...
//      [--markdown] [--jobs N]
int run_eval_outage(int argc, char** argv);

}  // namespace uwbnav::eval
