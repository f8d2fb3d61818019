// Cooperative ranging of the Navigator (docs/ekf.md "Neighbour ranges", issue 16
// item 1): the table of neighbour vehicles' broadcast states, and the range to a
// neighbour's tag fused as a range to a moving anchor whose position error
// (its claimed covariance, extrapolated to the range's time) is added to the
// measurement noise: a consider treatment, so nothing of the neighbour is estimated
// and nothing it shares with us is counted twice (neighbours whose own state is
// cooperative are refused by default).
#include <cmath>

#include "estimator/mm_range.hpp"
#include "estimator/navigator.hpp"

#if UWBNAV_COOP
namespace uwbnav {
namespace {

int64_t diff_us(uint64_t a, uint64_t b) { return static_cast<int64_t>(a) - static_cast<int64_t>(b); }
Real seconds(int64_t dt_us) { return static_cast<Real>(dt_us) * Real(1e-6); }

// A neighbour that does not report its velocity may move this fast [m/s] (1-sigma
// per axis) between its broadcast and the range.
constexpr Real kUnknownSpeedSigma_mps = Real(3);

// The claimed covariance (xx, xy, xz, yy, yz, zz) is finite and positive definite
// (leading minors of the symmetric 3x3 matrix all > 0).
bool covariance_ok(const float (&c)[6]) {
  for (float v : c) {
    if (!std::isfinite(v)) return false;
  }
  const Real xx = c[0], xy = c[1], xz = c[2], yy = c[3], yz = c[4], zz = c[5];
  if (!(xx > Real(0) && yy > Real(0) && zz > Real(0))) return false;
  if (!(xx * yy - xy * xy > Real(0))) return false;
  const Real det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  return det > Real(0);
}

}  // namespace

Status Navigator::on_neighbour_state(const NeighbourState& state) {
  if (!configured_) return Status::kNotInitialised;
  if (!is_vehicle_id(state.vehicle_id) || !std::isfinite(state.pos_nav_m.x) || !std::isfinite(state.pos_nav_m.y) ||
      !std::isfinite(state.pos_nav_m.z) || !covariance_ok(state.cov_pos_m2)) {
    return Status::kInvalidArgument;
  }
  NeighbourSlot* slot = nullptr;
  NeighbourSlot* free_slot = nullptr;
  NeighbourSlot* stalest = &neighbours_[0];
  for (NeighbourSlot& n : neighbours_) {
    if (n.state.vehicle_id == state.vehicle_id) slot = &n;
    if (n.state.vehicle_id == kNoVehicleId && free_slot == nullptr) free_slot = &n;
    if (n.state.rx_t_us < stalest->state.rx_t_us) stalest = &n;
  }
  if (slot != nullptr) {
    if (state.t_us < slot->state.t_us) return Status::kInvalidArgument;
  } else if (free_slot != nullptr) {
    slot = free_slot;
    *slot = NeighbourSlot{};
  } else {
    slot = stalest;
    *slot = NeighbourSlot{};
    ++diag_.neighbour_evictions;
  }
  slot->state = state;
  ++diag_.neighbour_states;
  return Status::kOk;
}

// UWB does not pass through a car: a range whose line of sight passes within
// coop.occluder_m of another neighbour's position (its state moved on to the
// range's time) is lengthened by the detour and is not fused. Only the cars
// that broadcast are known; the others are the gate's business.
bool Navigator::occluded(uint64_t t_us, const NeighbourSlot* target, const Vec3& tag_nav_m,
                         const Vec3& target_nav_m) const {
  if (!(cfg_.coop_occluder_m > Real(0))) return false;
  const Vec3 seg = target_nav_m - tag_nav_m;
  const Real len2 = seg.squaredNorm();
  if (!(len2 > Real(0))) return false;
  for (const NeighbourSlot& n : neighbours_) {
    if (&n == target || n.state.vehicle_id == kNoVehicleId) continue;
    const int64_t age_us = diff_us(t_us, n.state.t_us);
    if (static_cast<uint64_t>(age_us < 0 ? -age_us : age_us) > cfg_.coop_max_age_us) continue;
    Vec3 c = to_vec3(n.state.pos_nav_m);
    const Vec3 v = to_vec3(n.state.vel_nav_mps);
    if (v.allFinite()) c += v * seconds(age_us);
    const Real s = std::fmin(std::fmax((c - tag_nav_m).dot(seg) / len2, Real(0)), Real(1));
    if ((tag_nav_m + s * seg - c).squaredNorm() < cfg_.coop_occluder_m * cfg_.coop_occluder_m) return true;
  }
  return false;
}

bool Navigator::cooperative_at(uint64_t t_us) const {
  return diag_.last_neighbour_used_t_us != 0 && t_us >= diag_.last_neighbour_used_t_us &&
         t_us - diag_.last_neighbour_used_t_us <= cfg_.coop_hold_us;
}

RangeReport Navigator::on_neighbour_range(const UwbRange& range, RangeReport rep) {
  ++diag_.neighbour_ranges;
  const auto reject = [&](NeighbourVerdict v) {
    ++diag_.neighbour_rejected[static_cast<size_t>(v)];
    ++diag_.ranges_rejected;
    ++cycle_rejected_;
    rep.used = false;
    return rep;
  };
  if (!cfg_.coop_enable) return reject(NeighbourVerdict::kDisabled);
  const int ti = site_.num_tags == 0 ? 0 : site_.find_tag(range.tag_id);
  NeighbourSlot* slot = nullptr;
  for (NeighbourSlot& n : neighbours_) {
    if (n.state.vehicle_id == range.anchor_id) slot = &n;
  }
  if (slot == nullptr || ti < 0 || static_cast<size_t>(ti) >= kMaxTags || !std::isfinite(range.range_m)) {
    return reject(NeighbourVerdict::kUnknown);
  }
  const NeighbourState& nb = slot->state;
  if (nb.cooperative && !cfg_.coop_accept_dependent) return reject(NeighbourVerdict::kDependent);
  if (!(std::sqrt(std::fmax(nb.cov_pos_m2[0], nb.cov_pos_m2[3])) <= static_cast<float>(cfg_.coop_max_sigma))) {
    return reject(NeighbourVerdict::kUncertain);
  }
  const int64_t age_us = diff_us(range.t_us, nb.t_us);
  if (static_cast<uint64_t>(age_us < 0 ? -age_us : age_us) > cfg_.coop_max_age_us) {
    return reject(NeighbourVerdict::kStale);
  }
  if (phase_ != Phase::kRunning) return reject(NeighbourVerdict::kNoFilter);
  if (!cv_mode_ && !imu_alive(range.t_us)) enter_cv_mode(NavMode::kUwbOnly);
  if (!advance_cv(range.t_us)) return reject(NeighbourVerdict::kNoFilter);

  // The neighbour's tag at the range's time: its broadcast moved on with its
  // velocity; an unknown acceleration (coop.extrap_accel), or an unknown velocity,
  // widens its covariance.
  const Real dt_nb = seconds(age_us);
  Vec3 p_nb = to_vec3(nb.pos_nav_m);
  const Vec3 v_nb = to_vec3(nb.vel_nav_mps);
  Real extrap_sd = Real(0.5) * cfg_.coop_extrap_accel * dt_nb * dt_nb;
  if (v_nb.allFinite()) {
    p_nb += v_nb * dt_nb;
  } else {
    extrap_sd += kUnknownSpeedSigma_mps * std::fabs(dt_nb);
  }
  Mat3 p_cov;
  p_cov << nb.cov_pos_m2[0], nb.cov_pos_m2[1], nb.cov_pos_m2[2], nb.cov_pos_m2[1], nb.cov_pos_m2[3],
      nb.cov_pos_m2[4], nb.cov_pos_m2[2], nb.cov_pos_m2[4], nb.cov_pos_m2[5];
  p_cov.diagonal().array() += extrap_sd * extrap_sd;

  // Our tag's offset and the range scale are states; the neighbour's tag
  // offset (antenna delay) is not: its prior variance joins the noise.
  RangeErrorSlots es;
  es.tag_index = ti;
  es.anchor_slot = -1;
  const Real dt_r = seconds(diff_us(range.t_us, t_state_us_));
  const RangePrediction pred = mm_range_predict(ekf_.state(), ekf_.dcm(),
                                                cv_mode_ ? Vec3::Zero() : last_gyro_body_radps_, model_lever(ti),
                                                p_nb, dt_r, es);
  if (!pred.valid) return reject(NeighbourVerdict::kGate);
  if (occluded(range.t_us, slot, pred.tag_pos_nav_m, p_nb)) {
    rep.nlos = true;
    return reject(NeighbourVerdict::kOccluded);
  }
  const Real var_nb = pred.los_nav.dot(p_cov * pred.los_nav) + cfg_.tag_bias_sigma * cfg_.tag_bias_sigma;
  const Real hph = ekf_.prepare(pred.h);
  const Real s_one = hph + r_los_m2_ + var_nb;
  const Real innov = static_cast<Real>(range.range_m) - pred.range_m;
  rep.innovation_m = static_cast<float>(innov);
  rep.innovation_var_m2 = static_cast<float>(s_one);
  // Gate with the single-range variance: a range lengthened by a car in the
  // line of sight, or a neighbour whose claim is wrong, is refused.
  if (!(innov * innov <= cfg_.coop_gate_sigma * cfg_.coop_gate_sigma * s_one)) {
    rep.nlos = true;
    return reject(NeighbourVerdict::kGate);
  }
  // The neighbour's error is correlated in time (its filter's error, its tag
  // delay): ranges to it within 2T carry about one sample of it, so its share
  // of the variance is weighted by 2T / dt (dt: since the previous fused range
  // to that vehicle), as the GNSS fixes are (docs/ekf.md "GNSS").
  Real corr = Real(1);
  if (slot->used && cfg_.coop_corr_time > Real(0)) {
    const Real dt_prev = std::fmax(seconds(diff_us(range.t_us, slot->prev_fused_us)), Real(0.01));
    corr = std::fmax(Real(1), Real(2) * cfg_.coop_corr_time / dt_prev);
  }
  // Our own range-error states are consider states here: an offset learnt
  // against a moving, uncertain anchor would be the neighbour's error.
  const bool used = ekf_.update_prepared(innov, r_los_m2_ + corr * var_nb, true).applied;
  check_health(false);
  if (!used || phase_ != Phase::kRunning) return reject(NeighbourVerdict::kNoFilter);
  rep.used = true;
  ++diag_.neighbour_used;
  ++diag_.ranges_used;
  ++cycle_used_;
  diag_.last_neighbour_used_t_us = range.t_us;
  slot->prev_fused_us = range.t_us;
  slot->used = true;
  return rep;
}

}  // namespace uwbnav
#endif
