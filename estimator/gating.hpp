// NLOS gating layer between validated UWB ranges and the EKF: per-range
// evidence (SVM p1, consistency p2, Dempster–Shafer R, RAIM, innovation gate,
// channel diagnostics) and the selected fusion policy's decision.
// Static memory only; bounded cost per range.
#pragma once

#include <cstdint>

#include "estimator/params.hpp"
#include "estimator/types.hpp"

namespace uwbnav {

// Selectable policy (parameter gate.policy). Values are stable (parameter file).
enum class GatingPolicy : uint8_t {
  kNone = 0,        // fuse everything
  kInnovation = 1,  // innovation chi-square gate (gate in sigmas)
  kSvm = 2,         // seed 000 SVM p1 > 0.5 -> NLOS
  kConsistency = 3, // seed 000 eq. 3-6 consistency model p2
  kDempsterShafer = 4,  // seed 000 eq. 7-8, R > 0.8, §1.3 dynamic policy
  kResidualInflation = 5,  // seed 003 eq. 21-25: inflate R for large residuals
  kRaim = 6,        // seed 001 chi-square global test + local test, exclude, repeat
  kDefault = 7,     // the project's combined policy (docs/nlos.md)
};

// What the filter knows when a range arrives. Filled by the Navigator.
struct RangeContext {
  UwbRange range;                 // the validated measurement
  int anchor_index = -1;          // index into SiteConfig::anchors
  Vec3f anchor_pos_nav_m;         // anchor position [m]
  Vec3f tag_pos_nav_m;            // predicted tag antenna position at range.t_us [m]
  float predicted_range_m = kNaNf;   // h(x) at range.t_us [m]
  float innovation_m = kNaNf;        // range_m - predicted_range_m [m]
  float innovation_var_m2 = kNaNf;   // H P H^T + R with nominal R [m^2]
  float meas_var_m2 = kNaNf;         // nominal R = sigma_uwb^2 [m^2]
  float speed_mps = kNaNf;           // filter speed, horizontal [m/s] (v_ik of seed 000)
  float dist_since_prev_m = kNaNf;   // travelled distance of the tag since this
                                     // anchor/tag pair's previous range, from the
                                     // inertial/filter solution (Δd_k of eq. 3) [m]
  bool filter_ready = false;         // filter initialised and converged enough to trust predictions
  bool innovation_is_evidence = true;  // false: the filter learns no range error, so each of a pair's
                                       // innovations carries the same unlearned offset: a long one is
                                       // no NLOS evidence (default policy)
  bool inertial = false;  // the prediction comes from the IMU filter, which can coast through NLOS
};

// The gating layer's verdict on one range.
struct GatingDecision {
  bool use = true;           // fuse this range
  bool nlos = false;         // classified NLOS
  float r_scale = 1.0F;      // multiply nominal R by this (>= 1) when fused
  float r_add_m2 = 0.0F;     // then add this to R [m^2] (an NLOS range fused: the spread of its excess)
  bool bound = false;        // an NLOS range fused: a short one as a bound, a long one on a starved geometry by
                             // moment matching (docs/nlos.md); not learnt from (offsets, ranging noise)
  float excess_m = 0.0F;     // expected NLOS excess subtracted from the range before it is fused [m]
  float p_svm = kNaNf;       // p1, NaN if not computed
  float p_mc = kNaNf;        // p2, NaN if not computed
  float p_fused = kNaNf;     // R of eq. 8 or the policy's final NLOS probability
};

// The gating layer the Navigator owns. Implementation: estimator/nlos/gating_layer.cpp.
// Per-anchor state (hysteresis, previous range for eq. 1/3, escape counters)
// lives inside; fixed capacity kMaxAnchors x kMaxTags.
class GatingLayer;

}  // namespace uwbnav
