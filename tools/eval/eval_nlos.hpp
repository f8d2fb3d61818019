// `uwbnav eval nlos`: NLOS identification table in the form of seed 000 Table 2
// (precision / recall / accuracy per method) on (a) the simulated seed 000
// protocol, (b) simulated geometric NLOS drives, (c) a real labelled channel
// feature table (cross-validated), and the positioning table in the form of
// Table 3 (RMSE / MAX / STD) for IMU only, LS-UWB, the EKF with each policy.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "estimator/gating.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/eval/metrics.hpp"

namespace uwbnav::eval {

// Confusion counts with NLOS as the positive class (seed 000 eq. 11-13).
struct Confusion {
  size_t tp = 0, fp = 0, tn = 0, fn = 0;
  void add(bool truth_nlos, bool said_nlos);
  void add(const Confusion& o);
  size_t n() const { return tp + fp + tn + fn; }
  double precision() const;  // TP / (TP + FP), NaN when undefined
  double recall() const;     // TP / (TP + FN)
  double accuracy() const;   // (TP + TN) / n
  double false_alarm_rate() const;  // FP / (FP + TN): LOS ranges called NLOS
};

// One row of the identification table: a gating configuration run through the Navigator.
struct NlosMethod {
  std::string name;
  GatingPolicy policy = GatingPolicy::kNone;
  std::vector<std::pair<std::string, float>> params;  // extra overrides
};

// The methods of the table, in print order.
std::vector<NlosMethod> nlos_methods();

// Replays `rec` with the method's parameters and scores the NLOS decisions of
// the ranges whose index is in `subset` (indices into rec.uwb; empty = all labelled).
// Also returns the horizontal errors of the solution against truth.
[[nodiscard]] Status score_method(const dataset::Recording& rec, const NlosMethod& method,
                                  const std::vector<size_t>& subset, Confusion& confusion,
                                  std::vector<ErrorSample>* errors, std::string* error);

// `uwbnav eval nlos [options]` (argv[0] is "nlos"). Exit code 0 on success.
int run_eval_nlos(int argc, char** argv);

}  // namespace uwbnav::eval
