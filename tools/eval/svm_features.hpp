// Labelled NLOS feature samples for SVM training and evaluation, from format v1
// recordings (seed 000 eq. 1 range rate + vehicle speed) and from feature
// tables such as hanyang_static_nlos_features.csv (channel diagnostics).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/nlos/svm_model.hpp"
#include "estimator/status.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::eval {

struct SvmSample {
  float features[kSvmMaxFeatures] = {};  // raw (unscaled) features, svm_build_features order
  int label = 0;                         // 1 NLOS, 0 LOS
  int group = 0;                         // grouping for grouped cross-validation (position, run)
  size_t source_index = 0;               // row in the recording's uwb / the table
};

// Parses "rr" / "range_rate", "rrs" / "range_rate_speed", "channel".
bool parse_feature_set(const std::string& name, SvmFeatureSet* out);
const char* feature_set_name(SvmFeatureSet set);

// Horizontal truth speed at t_us by a central difference over +-dt_us [m/s]; NaN outside truth.
double truth_speed_mps(const std::vector<dataset::TruthRow>& truth, uint64_t t_us, uint64_t dt_us = 50000);

// Samples of a recording: for every labelled range whose anchor/tag pair had a
// previous range at most max_dt_us earlier, v_uk = (rho_k - rho_k-1) / dt
// (seed 000 eq. 1) and v_ik = horizontal truth speed at the range time.
// The firmware feeds the filter's speed instead; its error (a few cm/s) is
// negligible against the feature scale (m/s to tens of m/s). Channel features
// come from the range's fp/rx powers (ranges without them are skipped).
// group = anchor id. Needs truth for kRangeRateSpeed.
[[nodiscard]] Status samples_from_recording(const dataset::Recording& rec, SvmFeatureSet set, uint64_t max_dt_us,
                                            std::vector<SvmSample>& out, std::string* error);

// Samples of a labelled feature table (CSV with header; columns label,
// fp_power_dbm, rx_power_dbm required for kChannel). Rows with missing values
// are skipped. group = the static position (height_cm, horiz_dist_m) when the
// table has those columns, so that cross-validation can hold whole positions out.
// `path` may be stored gzip-compressed as `path`.gz (read when `path` is absent).
[[nodiscard]] Status samples_from_table(const std::string& path, SvmFeatureSet set, std::vector<SvmSample>& out,
                                        std::string* error);

}  // namespace uwbnav::eval
