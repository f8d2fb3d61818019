// `uwbnav calibrate`: per anchor/tag pair range offsets (measured minus true
// range, the antenna delays of both ends) from commissioning recordings, by
// robust batch least squares (docs/commissioning.md):
//   r_i = |a_anchor(i) - x_tag(i)(t_i)| + b_pair(i) + e_i
// with the tag positions x_tag taken from a reference (truth.csv with
// attitude, or surveyed static points) or, without a reference, estimated
// jointly with the offsets (self-calibration) as a piecewise-linear trajectory
// of the level vehicle (x, y, yaw per knot; z per knot or one per recording).
// Robust: IRLS with Huber weights on per-pair robust scales and rejection of
// residuals beyond reject_k sigma. Uncertainty: the LS covariance, scaled by
// the residual variance factor and by each pair's AR(1) autocorrelation.
// Offset combinations the data cannot separate (the gauge) are detected from
// that covariance and reported instead of a number. Host only.
#pragma once

#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "estimator/types.hpp"
#include "tools/calib/static_points.hpp"
#include "tools/dataset/calibration.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::calib {

enum class Method : uint8_t {
  kAuto = 0,    // truth when every recording has truth.csv, else static points when given for all, else self
  kTruth = 1,   // tag positions from truth.csv (body origin + attitude + lever arm)
  kStatic = 2,  // tag positions from surveyed static points (static_points.csv)
  kSelf = 3,    // no reference: trajectory and offsets estimated together
};
const char* method_name(Method m);

// Height model of the self-calibration trajectory.
enum class ZMode : uint8_t {
  kCommon = 0,  // one body-origin height per recording (flat floor), estimated
  kFree = 1,    // a height per knot (needs anchors at several heights)
  kFixed = 2,   // body-origin height fixed to Options::body_z_m
};

struct Options {
  Method method = Method::kAuto;
  std::vector<std::vector<StaticPoint>> static_points;  // per recording (kStatic); empty: none
  double knot_s = 0.0;              // self: trajectory knot spacing [s]; 0: auto (>= 0.1 s and >= 3 ranges
                                    // per unknown of a knot on average)
  ZMode z = ZMode::kCommon;         // self: height model
  double body_z_m = 0.0;            // self: initial (kCommon) or fixed (kFixed) body-origin height [m]
  double huber_k = 2.0;             // Huber threshold [robust sigma]
  double reject_k = 6.0;            // residuals beyond this are rejected [robust sigma]
  double prior_sigma_m = 1.0;       // weak prior on every offset (around 0) that keeps the gauge finite [m]
  bool fix_common = false;          // gauge: fix the mean of all offsets to common_offset_m
  double common_offset_m = 0.0;     // [m]
  double max_sigma_m = 0.02;        // an offset whose 1-sigma exceeds this is "not observable" [m]
  double accel_sigma_mps2 = 5.0;    // self: random-acceleration prior between knots [m/s^2]
  double yaw_accel_sigma_radps2 = 10.0;  // self: random angular acceleration prior [rad/s^2]
  double max_gap_s = 1.0;           // self: a gap in the ranges longer than this starts a new segment [s]
  double max_truth_gap_s = 0.5;     // truth: ranges between truth samples further apart are not used [s]
  int max_iterations = 40;
};

struct PairResult {
  uint16_t anchor_id = 0;
  uint8_t tag_id = 0;
  size_t ranges = 0;         // ranges of this pair that had a reference (or a knot)
  size_t used = 0;           // weight > 0
  size_t downweighted = 0;   // Huber weight < 1
  size_t rejected = 0;       // beyond reject_k
  double offset_m = 0.0;
  double sigma_m = std::numeric_limits<double>::quiet_NaN();     // reported 1-sigma [m]
  double ls_sigma_m = std::numeric_limits<double>::quiet_NaN();  // LS covariance before the AR(1) inflation [m]
  double rho = 0.0;          // lag-1 autocorrelation of the pair's residuals (capped at 0.95) [-]
  double batch_factor = 0.0; // variance factor from 5 s batch means (0: too few blocks) [-]
  double inflation = 1.0;    // sigma_m / ls_sigma_m: sqrt(max(AR(1) factor, batch factor)) [-]
  double scale_m = 0.0;      // robust scale (1.4826 MAD) of its residuals [m]
  double resid_rms_m = 0.0;  // RMS of the used residuals [m]
  // The slowly varying part of the residuals left after the offset (survey
  // error along the changing line of sight, multipath): square root of the
  // lag-1 autocovariance of its full-weight residuals in time order [m].
  double slow_sigma_m = 0.0;
  bool observable = false;
};

// offset_pair ~= d_anchor + d_tag with sum over tags of d_tag = 0.
struct Decomposition {
  bool testable = false;     // >= 2 anchors and >= 2 tags: the fit has redundancy
  std::vector<double> anchor_m, anchor_sigma_m;  // per site anchor
  std::vector<double> tag_m, tag_sigma_m;        // per site tag
  std::vector<double> resid_m;                   // per pair (PairResult order)
  double resid_rms_m = 0.0;
  double resid_max_m = 0.0;
  double chi2_per_dof = 0.0;
  size_t dof = 0;
};

// A combination of offsets the data do not determine to max_sigma_m.
struct WeakDirection {
  std::string what;
  double sigma_m = 0.0;
};

struct Result {
  Method method = Method::kAuto;     // the method used
  SiteConfig site;
  std::vector<PairResult> pairs;     // anchor-major, tag-minor over the site's tables
  Decomposition decomposition;
  double common_sigma_m = 0.0;       // 1-sigma of the mean of all offsets [m]
  // RMS of slow_sigma_m over the pairs that have consecutive full-weight
  // ranges: the range error a commissioned offset leaves on the commissioned
  // lines of sight; from a reference trajectory (kTruth) the file carries it
  // and the filter uses it in place of uwb.survey_sigma
  // (docs/commissioning.md "Systematic sigma") [m]; NaN: not measured
  double systematic_sigma_m = std::numeric_limits<double>::quiet_NaN();
  std::vector<WeakDirection> weak;
  bool observable = false;           // every pair's sigma <= max_sigma_m
  size_t ranges_total = 0;           // ranges in the recordings
  size_t ranges_no_reference = 0;    // no reference position (outside truth / static windows)
  size_t ranges_unknown = 0;         // anchor or tag not in the site
  size_t ranges_used = 0;
  size_t ranges_downweighted = 0;
  size_t ranges_rejected = 0;
  double resid_rms_m = 0.0;          // of the used ranges [m]
  double resid_p95_m = 0.0;          // 95th percentile of |residual| of all referenced ranges [m]
  double variance_factor = 1.0;      // weighted chi-square per degree of freedom
  int iterations = 0;
  bool converged = false;
  size_t knots = 0;                  // trajectory knots (self / static with unknown yaw)
  double knot_s = 0.0;               // self: knot spacing used [s]
  std::vector<double> body_z_m;      // self kCommon: estimated body-origin height per recording [m]
  std::vector<std::string> notes;
};

// Estimates the offsets of the site shared by `recs` (all must have the same
// anchors and tags). Non-kOk with `error` when the inputs cannot be used (no
// reference for the method, different sites, no ranges); an unobservable
// result is kOk with observable = false and `weak` filled.
[[nodiscard]] Status calibrate(const std::vector<dataset::Recording>& recs, const Options& options, Result& result,
                               std::string* error);

// The calibration file of an observable result (site sigma = the largest pair
// sigma; the systematic sigma from a reference trajectory only).
dataset::CalibrationFile to_calibration_file(const Result& result, const std::vector<std::string>& sources);

// Human-readable report: method, residual statistics, per pair offsets with
// sigma, the per-anchor/per-tag decomposition and any unobservable combination.
void print_report(std::FILE* out, const Result& result, const Options& options);

}  // namespace uwbnav::calib
