// NLOS gating layer: evidence per range, policy dispatch, epochs, hysteresis,
// escape and counters (docs/nlos.md).
#include "estimator/nlos/gating_layer.hpp"

#include <cmath>

#include "estimator/nlos/channel.hpp"
#include "estimator/nlos/consistency.hpp"
#include "estimator/nlos/dempster_shafer.hpp"
#include "estimator/nlos/innovation_evidence.hpp"
#include "estimator/nlos/residual_inflation.hpp"

namespace uwbnav {

namespace {

// Long NLOS ranges on a starved geometry (decide_default): the window in which
// the other anchors' latest ranges count [us], how many of them must have been
// heard in line of sight for NLOS ranges to be dropped, and how far the
// filter's own range variance must exceed the NLOS excess scale mu^2 (4: its
// range sigma above 2 mu, so that the mixture's mean shift is small against it).
constexpr uint64_t kGeometryWindowUs = 1000000;
constexpr int kMinLosAnchors = 2;
constexpr float kMomentUncertainty = 4.0F;
// Gain of the running share of agreeing ranges (decide_default): an EMA over
// about 1 / kShareGain = 50 ranges.
constexpr float kShareGain = 0.02F;
// Ranges a (re)started filter must have passed inside resid_th before its
// prediction outweighs long ranges in the escape (decide_default): as many as
// the share of agreeing ranges averages over.
constexpr uint32_t kVerifiedRanges = static_cast<uint32_t>(1.0F / kShareGain + 0.5F);

GatingPolicy policy_from_param(float value) {
  const long v = std::lround(value);
  if (v < 0 || v > static_cast<long>(GatingPolicy::kDefault)) return GatingPolicy::kDefault;
  return static_cast<GatingPolicy>(v);
}

float distance_m(const Vec3f& a, const Vec3f& b) {
  const float dx = a.x - b.x;
  const float dy = a.y - b.y;
  const float dz = a.z - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// The R scale of a range fused although it may be NLOS with probability p:
// R / (1 - p), the expected line-of-sight weight of the two-class mixture (EM),
// at most 100 R (p >= 0.99).
float los_weight_r_scale(float p_nlos) { return p_nlos < 0.99F ? 1.0F / (1.0F - p_nlos) : 100.0F; }

}  // namespace

GatingLayer::GatingLayer() = default;

Status GatingLayer::configure(const SiteConfig& site, const Params& params) {
  site_ = site;
  update_params(params);
  reset();
  Status status = Status::kOk;
  svm1_ = ok(svm_model_validate(kSvmModelRangeRate)) ? &kSvmModelRangeRate : nullptr;
  svm2_ = ok(svm_model_validate(kSvmModelRangeRateSpeed)) ? &kSvmModelRangeRateSpeed : nullptr;
  if (svm1_ == nullptr || svm2_ == nullptr) status = Status::kInvalidArgument;
  configured_ = true;
  return status;
}

void GatingLayer::update_params(const Params& params) {
  policy_ = policy_from_param(params[ParamId::kGatePolicy]);
  sigma_uwb_default_m_ = params[ParamId::kUwbSigma];
  innov_gate_sigma_ = params[ParamId::kGateInnovSigma];
  svm_model_ = static_cast<int>(std::lround(params[ParamId::kGateSvmModel]));
  svm_threshold_ = params[ParamId::kGateSvmThreshold];
  max_dt_us_ = param_us(params[ParamId::kGateMaxDtUs]);
  ds_nlos_ = params[ParamId::kGateDsNlos];
  ds_fuse_ = params[ParamId::kGateDsFuse];
  epoch_us_ = param_us(params[ParamId::kGateEpochUs]);
  resid_th_ = params[ParamId::kGateResidTh];
  resid_beta_ = params[ParamId::kGateResidBeta];
  const float pfa = params[ParamId::kGateRaimPfa];
  const float pfa_local = params[ParamId::kGateRaimPfaLocal];
  if (pfa != raim_pfa_ || pfa_local != raim_pfa_local_) {  // quantiles only when changed
    raim_compute_thresholds(pfa, pfa_local, raim_thresholds_);
    raim_pfa_ = pfa;
    raim_pfa_local_ = pfa_local;
  }
  chan_lo_db_ = params[ParamId::kGateChanLoDb];
  chan_hi_db_ = params[ParamId::kGateChanHiDb];
  chan_p_max_ = params[ParamId::kGateChanPMax];
  nlos_episode_s_ = params[ParamId::kGateNlosEpisode];
  los_episode_s_ = params[ParamId::kGateLosEpisode];
  escape_us_ = param_us(params[ParamId::kGateEscapeS] * 1e6F);
  escape_r_scale_ = params[ParamId::kGateEscapeRScale];
  default_nlos_ = params[ParamId::kGateDefaultNlos];
  nlos_bias_m_ = params[ParamId::kGateNlosBias];
  verify_frac_ = params[ParamId::kGateVerifyFrac];
  drift_frac_ = params[ParamId::kGateDriftFrac];
}

void GatingLayer::reset() {
  for (Slot& s : slots_) s = Slot{};
  on_filter_restart();
}

void GatingLayer::on_filter_restart() {
  last_pass_t_us_ = 0;
  seen_ready_ = false;
  escape_active_ = false;
  los_share_ = 1.0F;
  verified_ranges_ = 0;
}

GatingAnchorStats GatingLayer::anchor_stats(size_t anchor_index) const {
  GatingAnchorStats sum;
  if (anchor_index >= kMaxAnchors) return sum;
  uint64_t latest_t_us = 0;
  for (size_t t = 0; t < kMaxTags; ++t) {
    const Slot& s = slots_[anchor_index * kMaxTags + t];
    sum.los_count += s.stats.los_count;
    sum.nlos_count += s.stats.nlos_count;
    sum.used_count += s.stats.used_count;
    sum.held_count += s.stats.held_count;
    sum.escape_count += s.stats.escape_count;
    sum.nlos_state = sum.nlos_state || s.nlos_state;
    if (s.has_last && s.last_t_us >= latest_t_us) {
      latest_t_us = s.last_t_us;
      sum.last_p_nlos = s.stats.last_p_nlos;
    }
  }
  return sum;
}

int GatingLayer::anchors_heard(const RangeContext& ctx, size_t self, bool Slot::*flag, bool value) const {
  // A slot time-stamped after this range (out of order) wraps past the window.
  const size_t tag_index = self % kMaxTags;
  int n = 0;
  for (size_t a = 0; a < site_.num_anchors && a < kMaxAnchors; ++a) {
    const size_t i = a * kMaxTags + tag_index;
    const Slot& s = slots_[i];
    if (i == self || !s.has_last || s.*flag != value || ctx.range.t_us - s.last_t_us > kGeometryWindowUs) continue;
    ++n;
  }
  return n;
}

int GatingLayer::slot_index(const RangeContext& ctx) const {
  if (ctx.anchor_index < 0 || static_cast<size_t>(ctx.anchor_index) >= kMaxAnchors) return -1;
  const int tag = site_.find_tag(ctx.range.tag_id);
  const size_t tag_index = tag < 0 ? 0U : static_cast<size_t>(tag);
  return static_cast<int>(static_cast<size_t>(ctx.anchor_index) * kMaxTags + tag_index);
}

float GatingLayer::sigma_uwb_m(const RangeContext& ctx) const {
  if (std::isfinite(ctx.meas_var_m2) && ctx.meas_var_m2 > 0.0F) return std::sqrt(ctx.meas_var_m2);
  return sigma_uwb_default_m_;
}

float GatingLayer::svm_p(const SvmModel* model, const Evidence& e, const RangeContext& ctx) const {
  if (model == nullptr) return kNaNf;
  float features[kSvmMaxFeatures] = {};
  if (!svm_build_features(static_cast<SvmFeatureSet>(model->feature_set), e.range_rate_mps, ctx.speed_mps,
                          ctx.range.fp_power_dbm, ctx.range.rx_power_dbm, features)) {
    return kNaNf;
  }
  const Result<float> p = svm_nlos_probability(*model, features);
  return p.ok() ? p.value() : kNaNf;
}

GatingLayer::Evidence GatingLayer::compute_evidence(const RangeContext& ctx, const Slot& slot) const {
  Evidence e;
  if (slot.has_prev && ctx.range.t_us > slot.prev_t_us && ctx.range.t_us - slot.prev_t_us <= max_dt_us_) {
    // Float only (no soft-double on the M4F): dt_us <= max_dt_us is exact in float below
    // 2^24 us, the division by the exact 1e6 is correctly rounded.
    const float dt_s = static_cast<float>(ctx.range.t_us - slot.prev_t_us) / 1e6F;
    e.delta_range_m = ctx.range.range_m - slot.prev_range_m;  // Δρ_k (eq. 3)
    e.range_rate_mps = e.delta_range_m / dt_s;                // v_uk (eq. 1)
  }
  // The SVM (the costliest evidence) runs only for the policies that read it; the default
  // policy evaluates its coarse models itself, only when it uses them (decide_default).
  if (policy_ == GatingPolicy::kSvm || policy_ == GatingPolicy::kDempsterShafer) {
    e.p_svm = svm_p(svm_model_ == 1 ? svm1_ : svm2_, e, ctx);
  }
  e.p_mc = consistency_p_nlos(e.delta_range_m, ctx.dist_since_prev_m, sigma_uwb_m(ctx));
  e.p_chan = channel_p_nlos(ctx.range.fp_power_dbm, ctx.range.rx_power_dbm, chan_lo_db_, chan_hi_db_, chan_p_max_);
  if (ctx.filter_ready && ctx.innovation_var_m2 > 0.0F) {
    e.z = std::fabs(ctx.innovation_m) / std::sqrt(ctx.innovation_var_m2);
  }
  return e;
}

GatingDecision GatingLayer::decide_innovation(const RangeContext& ctx, const Evidence& e) const {
  GatingDecision d;
  if (!ctx.filter_ready) return d;  // no prediction to test against
  // Chi-square gate in sigmas: innov^2 / (gate^2 S) > 1 rejects; non-finite rejects.
  const float ratio = (ctx.innovation_m * ctx.innovation_m) /
                      (innov_gate_sigma_ * innov_gate_sigma_ * ctx.innovation_var_m2);
  if (!std::isfinite(ratio) || !(ctx.innovation_var_m2 > 0.0F) || ratio > 1.0F) {
    d.use = false;
    d.nlos = true;
  }
  (void)e;
  return d;
}

GatingDecision GatingLayer::decide_svm(const Evidence& e) const {
  GatingDecision d;
  d.p_fused = e.p_svm;
  d.nlos = e.p_svm > svm_threshold_;  // NaN (no previous range) -> LOS
  d.use = !d.nlos;
  return d;
}

GatingDecision GatingLayer::decide_consistency(const Evidence& e) const {
  GatingDecision d;
  d.p_fused = e.p_mc;
  d.nlos = e.p_mc > 0.5F;  // eq. 5: excess above σ_UWB
  d.use = !d.nlos;
  return d;
}

GatingDecision GatingLayer::decide_dempster_shafer(const RangeContext& ctx, const Evidence& e, int slot) const {
  GatingDecision d;
  const float r = ds_combine(e.p_svm, e.p_mc);  // eq. 7-8
  d.p_fused = r;
  d.nlos = r > ds_nlos_;
  // Seed 000 §1.3 over the epoch (latest range of each pair within epoch_us, this one included):
  // all LOS -> fuse; NLOS fewer than half -> fuse ranges whose R is below ds_fuse; otherwise drop.
  size_t n = 1;
  size_t n_nlos = d.nlos ? 1U : 0U;
  for (size_t i = 0; i < kSlots; ++i) {
    const Slot& s = slots_[i];
    if (static_cast<int>(i) == slot || !s.has_last || ctx.range.t_us - s.last_t_us > epoch_us_) continue;
    ++n;
    if (s.last_nlos) ++n_nlos;
  }
  if (n_nlos == 0) {
    d.use = true;
  } else {
    d.use = 2 * n_nlos < n && r < ds_fuse_;
  }
  return d;
}

GatingDecision GatingLayer::decide_residual(const RangeContext& ctx, const Evidence& e) const {
  GatingDecision d;
  if (!ctx.filter_ready) return d;
  // Seed 003 eq. 21-23 on the normalised residual; applied as R' = e R.
  const float factor = residual_inflation_factor(e.z, resid_th_, resid_beta_);
  if (!std::isfinite(factor)) {
    d.use = false;
    d.nlos = true;
    return d;
  }
  d.nlos = factor > 1.0F;
  d.r_scale = factor;
  return d;
}

GatingDecision GatingLayer::decide_raim(const RangeContext& ctx, int slot) const {
  GatingDecision d;
  // Epoch of this tag: the latest range of each anchor within epoch_us. With a
  // converged filter each older range is moved to this range's time with the
  // filter's own displacement (short-term INS motion is accurate even when the
  // absolute position is not); otherwise it is taken as measured.
  LsRange ranges[kRaimMaxRanges];
  size_t n = 0;
  size_t self = 0;
  const size_t tag_index = static_cast<size_t>(slot) % kMaxTags;
  const float sigma_m = sigma_uwb_m(ctx);
  for (size_t a = 0; a < site_.num_anchors && a < kMaxAnchors && n < kRaimMaxRanges; ++a) {
    const int i = static_cast<int>(a * kMaxTags + tag_index);
    const Slot& s = slots_[i];
    LsRange r;
    r.anchor_pos_nav_m = site_.anchors[a].pos_nav_m;
    r.sigma_m = sigma_m;
    if (i == slot) {
      r.range_m = ctx.range.range_m;
      self = n;
    } else {
      if (!s.has_last || ctx.range.t_us - s.last_t_us > epoch_us_) continue;
      r.range_m = s.last_range_m;
      if (ctx.filter_ready && s.last_filter_ready) {
        r.range_m += distance_m(r.anchor_pos_nav_m, ctx.tag_pos_nav_m) -
                     distance_m(r.anchor_pos_nav_m, s.last_tag_pos_nav_m);
      }
    }
    ranges[n++] = r;
  }
  LsOptions opt;
  opt.two_d = ctx.filter_ready && site_.platform == Platform::kGround;
  opt.known_z_m = ctx.tag_pos_nav_m.z;
  opt.has_initial_guess = ctx.filter_ready;
  opt.initial_guess_nav_m = ctx.tag_pos_nav_m;
  RaimResult result;
  if (!ok(raim_run(ranges, n, opt, raim_thresholds_, result))) return d;
  d.nlos = result.excluded[self];
  d.use = !d.nlos;
  return d;
}

GatingDecision GatingLayer::decide_default(const RangeContext& ctx, const Evidence& e, Slot& slot) {
  GatingDecision d;
  // sqrt(S) once per range: the gross rule, the bound and the escape all read it.
  const float sqrt_s = ctx.innovation_var_m2 > 0.0F ? std::sqrt(ctx.innovation_var_m2) : kNaNf;
  const float p_innov_full =
      ctx.filter_ready ? innovation_p_nlos(ctx.innovation_m, ctx.innovation_var_m2, nlos_bias_m_) : kNaNf;
  const float p_innov =
      ctx.innovation_is_evidence || !std::isfinite(p_innov_full) ? p_innov_full : std::fmin(p_innov_full, 0.5F);
  // With a prediction the normalised innovation supersedes the coarse models of seed 000
  // (SVM, consistency), which only read the same filter's speed and travelled distance and
  // measurably add false alarms (docs/nlos.md); they decide while the filter is not ready.
  // The coarse models also give way to channel diagnostics when the radio reports them
  // (measured: they add false alarms there). Before the filter runs there is no speed
  // either: the range-rate-only SVM1 is used then.
  // A filter that learns no range error (the ranges-only filter without an
  // IMU: its offsets are consider states) predicts each pair with the same
  // unlearned offset range after range. A long innovation there may be that
  // offset, and the episode chain below would count it again with every range
  // (measured on the trolley3 cell, offsets of 0.1-0.3 m: 24 % of the ranges
  // held out, 77 % of them line of sight, the position pulled off by the
  // pairs left out): its innovation testifies line of sight only (at most
  // neutral, 0.5). Nor do the coarse models run there: they read that
  // filter's speed and travelled distance. The channel (filter-independent)
  // and the gross gate decide NLOS there.
  const bool have_innov = std::isfinite(p_innov);
  const bool coarse = ctx.innovation_is_evidence && !have_innov && !std::isfinite(e.p_chan);
  float p_coarse = kNaNf;
  if (coarse) {
    p_coarse = svm_p(svm2_, e, ctx);
    if (!std::isfinite(p_coarse)) p_coarse = svm_p(svm1_, e, ctx);
  }
  const float evidence[4] = {p_coarse, coarse ? e.p_mc : kNaNf, e.p_chan, p_innov};
  const float r = ds_combine_all(evidence, 4);
  d.p_svm = p_coarse;  // the SVM that ran (SVM2, else SVM1); NaN when the coarse models were not used
  // A gross outlier against the filter is rejected whatever the other evidence says;
  // a running but untrusted filter (large covariance) rejects long ranges at the
  // gate (NLOS only lengthens) and short ones, which say the filter is off, at
  // twice the gate.
  const bool gross = (std::isfinite(e.z) && e.z > innov_gate_sigma_) || (ctx.filter_ready && !std::isfinite(e.z)) ||
                     (!ctx.filter_ready && ctx.innovation_var_m2 > 0.0F &&
                      (ctx.innovation_m > innov_gate_sigma_ * sqrt_s ||
                       std::fabs(ctx.innovation_m) > 2.0F * innov_gate_sigma_ * sqrt_s));
  // NLOS episodes last (docs/nlos.md "Episodes"): a two-state Markov chain per
  // pair with mean episode and line-of-sight lengths predicts the pair's NLOS
  // probability from its previous posterior, p- = p e^(-dt/T_nlos) + (1 - p)(1 - e^(-dt/T_los)),
  // and the evidence (probabilities on balanced classes, i.e. likelihood ratios)
  // updates it: posterior odds = prior odds x evidence odds (the product of eq. 8).
  // The chain's stationary NLOS probability bounds the prediction from below:
  // a long line-of-sight history cannot make the pair arbitrarily trusted.
  const float p_stationary = nlos_episode_s_ / (nlos_episode_s_ + los_episode_s_);
  const bool step = slot.has_p_nlos && ctx.range.t_us >= slot.p_nlos_t_us;
  float stay = 0.0F;   // P(NLOS -> NLOS) over the time since the pair's previous range
  float enter = 1.0F;  // P(LOS -> NLOS) over it
  if (step) {
    const uint64_t dt_us = ctx.range.t_us - slot.p_nlos_t_us;
    const float dt_s = static_cast<float>(static_cast<uint32_t>(dt_us < 4000000000ULL ? dt_us : 4000000000ULL)) * 1e-6F;
    stay = std::exp(-dt_s / nlos_episode_s_);
    enter = 1.0F - std::exp(-dt_s / los_episode_s_);
  }
  const auto predict = [&](float p) {
    return step && std::isfinite(p) ? std::fmax(p * stay + (1.0F - p) * enter, p_stationary) : p_stationary;
  };
  const float prior = predict(slot.p_nlos);
  const float posterior = std::isfinite(r) ? ds_combine(r, prior) : prior;
  d.nlos = gross || posterior > default_nlos_;
  // Held: the evidence alone says line of sight, the episode says not yet.
  if (!gross && posterior > default_nlos_ && !(r > default_nlos_)) ++slot.stats.held_count;
  // The stored belief stays away from certainty so that the chain can turn.
  constexpr float kBeliefClip = 0.999F;
  slot.p_nlos = d.nlos ? std::fmin(std::fmax(posterior, default_nlos_), kBeliefClip) : std::fmin(posterior, default_nlos_);
  // A range fused although it may be NLOS weighs by its probability of line of sight.
  const float los_weight_scale = los_weight_r_scale(posterior);
  // The channel-only belief that robust mode reads: the same chain on the same
  // clock, fed by the fp/rx power gap alone (filter-independent). One range's
  // gap is noisy, and a range of an NLOS episode that reads line-of-sight-like
  // (the channel then says nothing: p = 0.5) stays NLOS until the chain lets
  // the episode end. NaN while the radio never reported a channel for the pair.
  if (std::isfinite(e.p_chan) || std::isfinite(slot.p_chan_nlos)) {
    const float chan_prior = predict(slot.p_chan_nlos);
    slot.p_chan_nlos = std::isfinite(e.p_chan) ? std::fmin(ds_combine(e.p_chan, chan_prior), kBeliefClip) : chan_prior;
  }
  slot.p_nlos_t_us = ctx.range.t_us;
  slot.has_p_nlos = true;
  slot.nlos_state = d.nlos;
  d.p_fused = posterior;
  // Short ranges are bounds (docs/nlos.md): NLOS only lengthens a range, so
  // whatever its class the true distance is at most the range, and a range
  // shorter than predicted (inside the gate) says the filter's distance is too
  // long under either class. While the filter's own range uncertainty
  // (S - R) exceeds the NLOS excess scale nlos_bias_m, a short range classified
  // NLOS is fused as that bound: at the range, without the line-of-sight
  // weight, its variance widened by the spread the NLOS excess would add
  // (exponential law with mean mu = nlos_bias_m: p (2 - p) mu^2 for NLOS
  // probability p). It never pulls the filter past the range. A converged filter
  // does not take bounds: picking the short side of the noise of its
  // NLOS-classified ranges would bias it toward those anchors.
  const bool short_in_gate = std::isfinite(ctx.innovation_m) && ctx.innovation_var_m2 > 0.0F &&
                             ctx.innovation_m < 0.0F &&
                             ctx.innovation_m > -innov_gate_sigma_ * sqrt_s;
  const bool uncertain = ctx.innovation_var_m2 - ctx.meas_var_m2 > nlos_bias_m_ * nlos_bias_m_;
  // Long ranges on a starved geometry (docs/nlos.md "Long NLOS ranges on a
  // starved geometry"): where fewer than two other anchors of this tag were
  // heard in line of sight within kGeometryWindowUs, dropping every NLOS range
  // leaves the position unobservable across the remaining lines of sight and
  // the filter drifts along a range circle. While the filter's own range
  // uncertainty (S - R) exceeds the NLOS excess scale by kMomentUncertainty,
  // a long NLOS range inside the gate is fused by moment matching of the
  // two-class mixture instead: shortened by the expected excess p mu, its
  // variance widened by the excess's spread p (2 - p) mu^2 (as the bounds).
  const bool long_in_gate = std::isfinite(ctx.innovation_m) && ctx.innovation_var_m2 > 0.0F &&
                            ctx.innovation_m >= 0.0F && ctx.innovation_m < innov_gate_sigma_ * sqrt_s;
  const bool very_uncertain =
      ctx.innovation_var_m2 - ctx.meas_var_m2 > kMomentUncertainty * nlos_bias_m_ * nlos_bias_m_;
  const bool moment = d.nlos && !gross && long_in_gate && very_uncertain &&
                      anchors_heard(ctx, static_cast<size_t>(&slot - slots_), &Slot::last_nlos, false) < kMinLosAnchors;
  d.bound = d.nlos && !gross && short_in_gate && uncertain;
  d.use = !d.nlos || d.bound || moment;
  if (d.bound || moment) {
    const float p = std::fmin(std::fmax(posterior, 0.0F), 1.0F);
    d.r_add_m2 = p * (2.0F - p) * nlos_bias_m_ * nlos_bias_m_;
    if (moment) d.excess_m = p * nlos_bias_m_;
    d.bound = true;  // not learnt from: offsets and noise see trusted ranges only
  } else if (d.use) {
    // Seed 003 inflation for accepted ranges with a large normalised residual.
    const float factor = residual_inflation_factor(e.z, resid_th_, resid_beta_);
    d.r_scale = std::fmax(std::isfinite(factor) ? factor : 1.0F, los_weight_scale);
  }
  // Robust mode (the escape): a filter whose innovations stopped matching its own
  // claim (running share of |innovation| < resid_th sqrt(S) below drift_frac), or that
  // fused nothing for escape_s while ranges kept arriving, may have drifted away from
  // its own gate. (Ranges held out as NLOS by their episode do not count as rejected.)
  // In robust mode every finite range is fused with R inflated by the seed 003 factor
  // of its residual (at least escape_r_scale): an iteratively reweighted update in
  // which the consistent ranges dominate. It ends when the share exceeds verify_frac.
  // The filter's covariance is honest by construction (range-error states, learned
  // noise, recovery by inflation in the Navigator), so a new filter starts trusted.
  // A filter that is not ready (large covariance) can starve just as well: its
  // coarse evidence reads its own lagging speed and flags every range (measured:
  // a pull-away at 2 m/s^2 under 47 % NLOS, no range fused for 15 s, 140 m off).
  // Its normalised innovation is honest (S carries the large covariance).
  const float z = std::isfinite(e.z) ? e.z
                  : ctx.innovation_var_m2 > 0.0F ? std::fabs(ctx.innovation_m) / sqrt_s
                                                 : kNaNf;
  // NLOS only lengthens a range (docs/nlos.md item 6, "Long ranges of a ready
  // filter"): to a ready filter a range longer than its prediction beyond
  // resid_th is what an NLOS path looks like, and it is evidence that the
  // filter left its ranges only when another anchor of the tag reads short
  // (a filter that moved away from an anchor reads that anchor short; no
  // NLOS path does). While no other anchor's latest range (within
  // kGeometryWindowUs) read short by more than one sigma of S, such a range
  // neither lowers the share nor starves the filter: where every anchor is
  // NLOS at once the IMU filter coasts instead of being dragged by long
  // ranges (measured: tuning drive ground_hard:15, six anchors NLOS while the
  // car braked to a stop; robust mode fused 1-4 m long ranges, one of them
  // moved the filter 0.5 m, 2.6 m off by the time it stood). Without the
  // short-anchor condition a filter that drifted toward a line-of-sight
  // anchor stayed locked out of it (tuning ground_nlos:31, 0.56 -> 1.02 m).
  // Only the IMU filter coasts: the ranges-only filter (no inertial
  // prediction; without an IMU its long innovations may be unlearned offsets)
  // keeps both tests, as does a filter that is not ready (a pull-away under
  // NLOS starves it with ranges of either sign) and a filter (re)started,
  // handed over, recovered or in robust mode less than kVerifiedRanges
  // confirmed ranges ago: its long ranges may be its own error (ground_hard:65,
  // tuning seeds 61-99: an IMU filter handed a wrong velocity ran 10 m off
  // without the escape).
  // (In robust mode verified_ranges_ is 0: the relief never acts there.)
  if (escape_us_ > 0 && std::isfinite(z)) {
    // A finite z means a finite innovation.
    const bool long_explained = ctx.inertial && ctx.filter_ready && verified_ranges_ >= kVerifiedRanges &&
                                ctx.innovation_m > 0.0F && !(z < resid_th_) &&
                                anchors_heard(ctx, static_cast<size_t>(&slot - slots_), &Slot::last_short, true) == 0;
    if (!long_explained) los_share_ += kShareGain * ((z < resid_th_ ? 1.0F : 0.0F) - los_share_);
    if (!seen_ready_) {
      seen_ready_ = true;
      last_pass_t_us_ = ctx.range.t_us;
    }
    if (long_explained && !escape_active_) last_pass_t_us_ = ctx.range.t_us;
    const bool starved = ctx.range.t_us - last_pass_t_us_ > escape_us_;
    if (!escape_active_ && (starved || los_share_ < drift_frac_)) {
      escape_active_ = true;
      ++escape_entries_;
      los_share_ = 0.0F;
      verified_ranges_ = 0;
    } else if (escape_active_ && los_share_ > verify_frac_) {
      escape_active_ = false;
    }
    if (escape_active_) {
      // Robust mode ignores the filter-derived evidence (SVM speed, consistency distance,
      // hysteresis): the plain chi-square gate on S plus seed 003 inflation, and the
      // filter-independent channel evidence. While the filter disagrees with most ranges
      // (share below drift_frac) or passes none (starved), every range is admitted.
      const bool channel_nlos = e.p_chan > default_nlos_;
      const bool in_gate = z <= innov_gate_sigma_;
      const bool admit_all = starved || los_share_ < drift_frac_;
      d.use = std::isfinite(ctx.innovation_m) && !channel_nlos && (in_gate || admit_all);
      d.bound = false;
      d.r_add_m2 = 0.0F;
      // excess_m stays: a long NLOS range of a starved geometry is still
      // shortened by its expected excess, weighted as robust mode weighs.
      if (d.use) {
        const float factor = residual_inflation_factor(z, resid_th_, resid_beta_);
        d.r_scale = std::isfinite(factor) ? std::fmax(factor, escape_r_scale_) : escape_r_scale_;
        // A pair in a channel NLOS episode weighs by the episode's probability
        // of line of sight, R / (1 - p), as a fused range does outside robust mode.
        if (slot.p_chan_nlos > default_nlos_) {
          d.r_scale = std::fmax(d.r_scale, los_weight_r_scale(slot.p_chan_nlos));
        }
        ++slot.stats.escape_count;
        if (in_gate) last_pass_t_us_ = ctx.range.t_us;
      }
    } else if (!d.nlos) {
      last_pass_t_us_ = ctx.range.t_us;
      if (ctx.filter_ready && z < resid_th_ && verified_ranges_ < kVerifiedRanges) ++verified_ranges_;
    }
  }
  return d;
}

GatingDecision GatingLayer::assess(const RangeContext& ctx) {
  GatingDecision d;
  if (!configured_) return d;
  const int si = slot_index(ctx);
  if (si < 0 || !std::isfinite(ctx.range.range_m)) {
    d.use = false;
    d.nlos = true;
    return d;
  }
  Slot& slot = slots_[si];
  const Evidence e = compute_evidence(ctx, slot);

  switch (policy_) {
    case GatingPolicy::kNone: break;
    case GatingPolicy::kInnovation: d = decide_innovation(ctx, e); break;
    case GatingPolicy::kSvm: d = decide_svm(e); break;
    case GatingPolicy::kConsistency: d = decide_consistency(e); break;
    case GatingPolicy::kDempsterShafer: d = decide_dempster_shafer(ctx, e, si); break;
    case GatingPolicy::kResidualInflation: d = decide_residual(ctx, e); break;
    case GatingPolicy::kRaim: d = decide_raim(ctx, si); break;
    case GatingPolicy::kDefault: d = decide_default(ctx, e, slot); break;
  }
  if (policy_ != GatingPolicy::kDefault) d.p_svm = e.p_svm;  // NaN where no SVM ran
  d.p_mc = e.p_mc;

  // This range becomes the pair's previous range (eq. 1/3) and its epoch entry.
  slot.has_prev = true;
  slot.prev_t_us = ctx.range.t_us;
  slot.prev_range_m = ctx.range.range_m;
  slot.has_last = true;
  slot.last_t_us = ctx.range.t_us;
  slot.last_range_m = ctx.range.range_m;
  slot.last_tag_pos_nav_m = ctx.tag_pos_nav_m;
  slot.last_filter_ready = ctx.filter_ready;
  slot.last_nlos = d.nlos;
  slot.last_short = ctx.filter_ready && ctx.innovation_var_m2 > 0.0F &&
                    ctx.innovation_m * ctx.innovation_m > ctx.innovation_var_m2 && ctx.innovation_m < 0.0F;
  if (d.nlos) {
    ++slot.stats.nlos_count;
  } else {
    ++slot.stats.los_count;
  }
  slot.stats.last_p_nlos = d.p_fused;
  return d;
}

void GatingLayer::on_result(const RangeContext& ctx, const GatingDecision& d, bool fused) {
  (void)d;
  if (!fused) return;
  const int si = slot_index(ctx);
  if (si >= 0) ++slots_[si].stats.used_count;
}

}  // namespace uwbnav
