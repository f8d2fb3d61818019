// The NLOS gating layer the Navigator owns: per-range evidence from the
// methods of estimator/nlos/ (SVM p1, consistency p2, Dempster-Shafer R,
// residual inflation, RAIM, innovation gate, channel diagnostics) and the
// selected policy's decision (GatingPolicy, docs/nlos.md). Per anchor/tag
// pair state for eq. 1/3 differences, epochs, NLOS episodes and counters; an
// escape for a filter locked out by its own gate. Static memory only;
// bounded cost per range (RAIM: at most kRaimMaxRanges LS solves).
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/gating.hpp"
#include "estimator/nlos/raim.hpp"
#include "estimator/nlos/svm_model.hpp"
#include "estimator/params.hpp"
#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav {

// Per-anchor counters and state (summed over tags) for diagnostics.
struct GatingAnchorStats {
  uint32_t los_count = 0;       // ranges classified LOS
  uint32_t nlos_count = 0;      // ranges classified NLOS
  uint32_t used_count = 0;      // ranges the Navigator fused
  uint32_t held_count = 0;      // ranges the evidence alone calls LOS, held NLOS by the episode prior
  uint32_t escape_count = 0;    // ranges admitted by the escape
  bool nlos_state = false;      // NLOS state of the episode model (any tag of this anchor)
  float last_p_nlos = kNaNf;    // last fused NLOS probability
};

class GatingLayer {
 public:
  GatingLayer();

  // Loads the site (anchor/tag tables) and the parameters, verifies the SVM
  // models (CRC); clears all state. kInvalidArgument when a model is corrupt
  // (the layer still works: SVM evidence is then absent).
  [[nodiscard]] Status configure(const SiteConfig& site, const Params& params);
  // Applies changed parameter values live; keeps per-anchor state.
  void update_params(const Params& params);
  // Clears per-anchor state (NLOS episodes, previous ranges, epochs, escape).
  void reset();
  // The filter was (re)started or changed its model (hand-over from the
  // ranges-only to the IMU filter, re-anchoring): its predictions are
  // unverified again, so the robust warm-up starts over; per-pair state stays.
  void on_filter_restart();
  // The filter was found inconsistent and recovered in place (covariance
  // inflated, re-anchored): its predictions must be confirmed by ranges again
  // before they outweigh long ranges (decide_default, kVerifiedRanges).
  void on_filter_unverified() { verified_ranges_ = 0; }

  // Verdict on one range, before the filter update. Never touches the filter.
  // Ranges must come in non-decreasing time (as the Navigator guarantees).
  GatingDecision assess(const RangeContext& ctx);
  // Feedback after the update: `fused` says whether the Navigator fused it (counters).
  void on_result(const RangeContext& ctx, const GatingDecision& d, bool fused);

  GatingPolicy policy() const { return policy_; }
  // Robust mode of the default policy: after escape_s without a passed range, or
  // when the share of agreeing ranges falls below drift_frac; long ranges of a
  // verified IMU filter while no anchor reads short count for neither (see
  // decide_default, docs/nlos.md).
  bool escape_active() const { return escape_active_; }
  uint32_t escape_entries() const { return escape_entries_; }
  // Counters of anchor `anchor_index` (index into SiteConfig::anchors).
  GatingAnchorStats anchor_stats(size_t anchor_index) const;

 private:
  static constexpr size_t kSlots = kMaxAnchors * kMaxTags;

  // Per anchor/tag pair. Members ordered by alignment (no padding holes:
  // kSlots of these are the largest part of the gating state).
  struct Slot {
    uint64_t prev_t_us = 0;
    // Latest range of the pair, for epochs (D-S dynamic policy, RAIM).
    uint64_t last_t_us = 0;
    float prev_range_m = 0.0F;
    float last_range_m = 0.0F;
    Vec3f last_tag_pos_nav_m;
    GatingAnchorStats stats;
    // Two-state Markov chain of the pair's NLOS state (default policy): the
    // posterior NLOS probability after the pair's latest range and its time.
    uint64_t p_nlos_t_us = 0;
    float p_nlos = 0.5F;
    // The same chain on the same clock (p_nlos_t_us), fed by the channel
    // evidence alone (fp/rx power gap): the filter-independent NLOS belief
    // that robust mode reads [-]. NaN until the radio reported a channel for
    // this pair.
    float p_chan_nlos = kNaNf;
    bool has_p_nlos = false;
    bool nlos_state = false;
    bool has_prev = false;
    bool has_last = false;
    bool last_filter_ready = false;
    bool last_nlos = false;
    // The latest range read shorter than a ready filter's prediction by more
    // than one sigma of S: what a filter that moved away from this anchor reads.
    bool last_short = false;
  };

  // Evidence of one range, computed once and shared by the policies.
  struct Evidence {
    float range_rate_mps = kNaNf;  // v_uk, eq. 1
    float delta_range_m = kNaNf;   // Δρ_k, eq. 3
    float p_svm = kNaNf;           // p1 of the selected model (policies svm and dempster-shafer only)
    float p_mc = kNaNf;            // p2, eq. 6
    float p_chan = kNaNf;          // channel evidence
    float z = kNaNf;               // |innovation| / sqrt(S) [-]
  };

  int slot_index(const RangeContext& ctx) const;
  // Other anchors of slot self's tag whose latest range, within
  // kGeometryWindowUs of this one, has `flag` equal to `value` (last_nlos
  // false: heard in line of sight; last_short true: read short).
  [[nodiscard]] int anchors_heard(const RangeContext& ctx, size_t self, bool Slot::*flag, bool value) const;
  float sigma_uwb_m(const RangeContext& ctx) const;
  Evidence compute_evidence(const RangeContext& ctx, const Slot& slot) const;
  float svm_p(const SvmModel* model, const Evidence& e, const RangeContext& ctx) const;

  GatingDecision decide_innovation(const RangeContext& ctx, const Evidence& e) const;
  GatingDecision decide_svm(const Evidence& e) const;
  GatingDecision decide_consistency(const Evidence& e) const;
  GatingDecision decide_dempster_shafer(const RangeContext& ctx, const Evidence& e, int slot) const;
  GatingDecision decide_residual(const RangeContext& ctx, const Evidence& e) const;
  GatingDecision decide_raim(const RangeContext& ctx, int slot) const;
  GatingDecision decide_default(const RangeContext& ctx, const Evidence& e, Slot& slot);

  SiteConfig site_;
  bool configured_ = false;
  const SvmModel* svm1_ = nullptr;  // validated models, nullptr when corrupt
  const SvmModel* svm2_ = nullptr;
  Slot slots_[kSlots];

  // Parameters.
  GatingPolicy policy_ = GatingPolicy::kDefault;
  float sigma_uwb_default_m_ = 0.1F;
  float innov_gate_sigma_ = 5.0F;
  int svm_model_ = 2;
  float svm_threshold_ = 0.5F;
  uint64_t max_dt_us_ = 500000;
  float ds_nlos_ = 0.8F;
  float ds_fuse_ = 0.7F;
  uint64_t epoch_us_ = 150000;
  float resid_th_ = 3.0F;
  float resid_beta_ = 2.0F;
  RaimThresholds raim_thresholds_;
  float raim_pfa_ = -1.0F;
  float raim_pfa_local_ = -1.0F;
  float chan_lo_db_ = 6.0F;
  float chan_hi_db_ = 10.0F;
  float chan_p_max_ = 0.99F;
  float nlos_episode_s_ = 2.0F;   // mean NLOS episode length [s]
  float los_episode_s_ = 20.0F;   // mean LOS stretch [s]
  uint64_t escape_us_ = 2000000;
  float escape_r_scale_ = 100.0F;
  float default_nlos_ = 0.5F;
  float nlos_bias_m_ = 0.5F;      // mean NLOS excess of the innovation evidence [m]
  float verify_frac_ = 0.35F;
  float drift_frac_ = 0.15F;

  // Escape state (default policy).
  uint64_t last_pass_t_us_ = 0;    // last range that passed the gate, or that a verified filter's NLOS explains
  bool seen_ready_ = false;         // the filter has been ready since the last reset
  bool escape_active_ = false;      // robust mode (warm-up or escape)
  uint32_t escape_entries_ = 0;
  float los_share_ = 0.0F;          // EMA of (|innovation| < resid_th sqrt(S)) while ready; long ranges a
                                    // verified IMU filter explains are left out
  uint32_t verified_ranges_ = 0;    // ranges a ready filter passed inside resid_th since it (re)started,
                                    // recovered or entered robust mode
};

}  // namespace uwbnav
