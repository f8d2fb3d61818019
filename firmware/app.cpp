// The 100 Hz application cycle (see app.hpp).
#include "firmware/app.hpp"

#include <cmath>
#include <cstddef>
#include <cstring>

#include "firmware/param_blob.hpp"

namespace uwbnav {
namespace {

// The commissioned range calibration of the board's site (docs/commissioning.md)
// is usable: either uncalibrated (sigma NaN, every offset zero) or a sigma in
// (0, 1] m with every offset of the site's pairs finite and within +-10 m; a
// systematic sigma, when given, belongs to a calibrated site and is in [0, 1] m.
bool site_calibration_valid(const SiteConfig& site) {
  const float sigma = site.range_offset_sigma_m;
  const bool calibrated = !std::isnan(sigma);
  if (calibrated && !(sigma > 0.0F && sigma <= 1.0F)) return false;
  const float sys_m = site.range_systematic_sigma_m;
  if (!std::isnan(sys_m) && !(calibrated && sys_m >= 0.0F && sys_m <= 1.0F)) return false;
  for (size_t a = 0; a < kMaxAnchors; ++a) {
    for (size_t t = 0; t < kMaxTags; ++t) {
      const float v = site.range_offset_m[a][t];
      if (!calibrated && v != 0.0F) return false;
      if (!std::isfinite(v) || std::fabs(v) > 10.0F) return false;
    }
  }
  return true;
}

}  // namespace

App::App(hal::Board& board) : board_(board) {}

Status App::init() {
  for (uint32_t& b : nav_base_) b = 0;  // the navigator's counters restart with configure()
  if (!site_calibration_valid(board_.site)) {
    initialised_ = false;
    return Status::kInvalidArgument;
  }
  params_.reset_all();
  ignore_status(load_params());  // empty or corrupt store: defaults stay
  validator_.configure(board_.site, params_);
  can_tx_.configure(params_);
  can_decoder_.configure(params_);
  hil_rx_enabled_ = params_[ParamId::kCanHilRxEnable] > 0.5F;
#if UWBNAV_COOP || UWBNAV_GNSS
  can_decoder_.set_hil_enabled(hil_rx_enabled_);
#endif
  const Status s = nav_.configure(board_.site, params_);
  initialised_ = ok(s);
  return s;
}

Status App::set_param(ParamId id, float value) {
  const Status s = params_.set(id, value);
  if (ok(s)) apply_params(params_);
  return s;
}

void App::apply_params(const Params& params) {
  params_ = params;
  validator_.update_params(params_);
  nav_.update_params(params_);
  can_tx_.configure(params_);
  can_decoder_.configure(params_);
  hil_rx_enabled_ = params_[ParamId::kCanHilRxEnable] > 0.5F;
#if UWBNAV_COOP || UWBNAV_GNSS
  can_decoder_.set_hil_enabled(hil_rx_enabled_);
#endif
}

Status App::save_params() {
  uint8_t blob[kParamBlobMaxBytes];
  const size_t n = param_blob_write(params_, blob, sizeof blob);
  if (n == 0) return Status::kFull;
  return board_.params.save(blob, n);
}

Status App::load_params() {
  uint8_t blob[kParamBlobMaxBytes];
  size_t n = 0;
  const Status s = board_.params.load(blob, sizeof blob, &n);
  if (!ok(s)) return s;
  Params loaded = params_;
  const Status r = param_blob_read(blob, n, loaded, nullptr);
  if (!ok(r)) return r;
  apply_params(loaded);
  return Status::kOk;
}

void App::reset_filter() {
  nav_.reset();
  validator_.reset_history();
}

// The counters of NavDiagnostics (imu_samples .. iterated_updates) are its leading
// uint32_t fields: `reset stats` keeps their values as an array and subtracts
// it in one loop (flash on the M4F).
static_assert(offsetof(NavDiagnostics, imu_samples) == 0 &&
                  offsetof(NavDiagnostics, iterated_updates) == (App::kNavCounters - 1) * sizeof(uint32_t),
              "NavDiagnostics counters are no longer the leading uint32_t fields");

void App::reset_stats() {
  stats_ = AppStats{};
  can_tx_.reset_stats();
  can_decoder_.reset_stats();
  std::memcpy(nav_base_, &nav_.diagnostics(), sizeof nav_base_);
  board_.can.reset_counters();
}

NavDiagnostics App::nav_counters() const {
  NavDiagnostics d = nav_.diagnostics();
  uint32_t c[kNavCounters];
  std::memcpy(c, &d, sizeof c);
  for (size_t i = 0; i < kNavCounters; ++i) c[i] -= nav_base_[i];
  std::memcpy(static_cast<void*>(&d), c, sizeof c);  // the leading counters only (static_assert above)
  return d;
}

void App::record_cycle_timing(uint32_t work_us, uint32_t jitter_us, bool overrun) {
  LoopStats& l = stats_.loop;
  if (l.cycles == 0 || work_us < l.cycle_min_us) l.cycle_min_us = work_us;
  if (work_us > l.cycle_max_us) l.cycle_max_us = work_us;
  if (jitter_us > l.jitter_max_us) l.jitter_max_us = jitter_us;
#if UWBNAV_LOOP_HISTOGRAM
  const uint32_t latency_us = jitter_us + work_us;
  if (latency_us > l.latency_max_us) l.latency_max_us = latency_us;
  ++l.latency_hist[latency_bin(latency_us)];
#endif
  l.cycle_sum_us += work_us;
  ++l.cycles;
  if (overrun) ++l.overruns;
}

bool App::accept_imu(const ImuSample& imu, uint64_t now_us, SourceStats& src) {
  ++src.received;
  const Verdict v = validator_.check_imu(imu, now_us);
  if (!v.accepted) {
    ++src.rejected[static_cast<size_t>(v.reason)];
    return false;
  }
  ++src.accepted;
  imu_buf_[imu_count_++] = imu;
  return true;
}

bool App::accept_uwb(const UwbRange& r, uint64_t now_us, SourceStats& src) {
  ++src.received;
  const Verdict v = validator_.check_uwb(r, now_us);
  if (!v.accepted) {
    ++src.rejected[static_cast<size_t>(v.reason)];
    return false;
  }
  ++src.accepted;
  uwb_buf_[uwb_count_++] = r;
  return true;
}

void App::drain_sensors(uint64_t now_us) {
  imu_count_ = 0;
  uwb_count_ = 0;
  ImuSample imu;
  while (imu_count_ < kMaxImuPerCycle) {
    const Status s = board_.imu.poll(now_us, imu);
    if (s == Status::kIoError) {
      ++stats_.imu.io_errors;
      break;
    }
    if (!ok(s)) break;
    ignore_result(accept_imu(imu, now_us, stats_.imu));
  }
  UwbRange r;
  while (uwb_count_ < kMaxUwbPerCycle) {
    const Status s = board_.uwb.poll(now_us, r);
    if (s == Status::kIoError) {
      ++stats_.uwb.io_errors;
      break;
    }
    if (!ok(s)) break;
    ignore_result(accept_uwb(r, now_us, stats_.uwb));
  }
#if UWBNAV_COOP || UWBNAV_GNSS
  // Neighbour states (V2X_Neighbour*) and GNSS fixes (GNSS_Fix*) arrive on the
  // vehicle bus with or without a HIL rig; the decoder drops the HIL sensor
  // groups when HIL is off.
  drain_can_sensors(now_us);
#else
  if (hil_rx_enabled_) drain_can_sensors(now_us);
#endif
}

// HIL rigs inject sensors as CAN frames (docs/can.md); the decoder checks the
// transport (E2E), the validator the physics, exactly as for any other source.
void App::drain_can_sensors(uint64_t now_us) {
  // Samples stamped after this cycle's deadline (the loop woke late and the
  // rig already sent them) wait for the next cycle instead of being "future".
  size_t kept = 0;
  for (size_t k = 0; k < can_pending_count_; ++k) {
    const can::CanSensorSample& p = can_pending_[k];
    const uint64_t t = p.kind == can::SensorKind::kImu ? p.imu.t_us : p.uwb.t_us;
    if (t > now_us) {
      can_pending_[kept++] = p;
    } else {
      accept_can_sample(p, now_us);
    }
  }
  can_pending_count_ = kept;
  hal::CanFrame f;
  for (size_t n = 0; n < kMaxCanRxPerCycle; ++n) {
    if (imu_count_ >= kMaxImuPerCycle || uwb_count_ >= kMaxUwbPerCycle) break;
    if (!ok(board_.can.receive(f))) break;
    can::CanSensorSample sample;
    const Status s = can_decoder_.on_frame(f, now_us, sample);
    if (s == Status::kRejected) {
      ++stats_.can_rx.received;
      ++stats_.can_rx.io_errors;
      continue;
    }
    if (!ok(s)) continue;
#if UWBNAV_COOP
    if (sample.kind == can::SensorKind::kNeighbour) {
      // A neighbour state carries its own latency; the validator judges it.
      accept_neighbour(sample.neighbour, now_us);
      continue;
    }
#endif
#if UWBNAV_GNSS
    if (sample.kind == can::SensorKind::kGnss) {
      // Fused after the cycle's IMU and ranges, with the board's fixes (drain_gnss).
      if (can_gnss_count_ < kMaxGnssPerCycle) {
        can_gnss_[can_gnss_count_++] = sample.gnss;
      } else {
        ++stats_.gnss.received;
        ++stats_.gnss.io_errors;  // more fixes in one cycle than kMaxGnssPerCycle: dropped
      }
      continue;
    }
#endif
    const uint64_t t = sample.kind == can::SensorKind::kImu ? sample.imu.t_us : sample.uwb.t_us;
    if (t > now_us && can_pending_count_ < kMaxCanPending) {
      can_pending_[can_pending_count_++] = sample;
      continue;
    }
    accept_can_sample(sample, now_us);
  }
}

void App::accept_can_sample(const can::CanSensorSample& sample, uint64_t now_us) {
  if (sample.kind == can::SensorKind::kImu && imu_count_ < kMaxImuPerCycle) {
    ignore_result(accept_imu(sample.imu, now_us, stats_.can_rx));
  } else if (sample.kind == can::SensorKind::kUwb && uwb_count_ < kMaxUwbPerCycle) {
    ignore_result(accept_uwb(sample.uwb, now_us, stats_.can_rx));
  }
}

void App::handle_range(const UwbRange& r) {
  const RangeReport rep = nav_.on_range(r);
  can_diag_.set_anchor_nlos(board_.site.find_anchor(rep.anchor_id), rep.nlos);
  if (observer_ != nullptr) observer_->on_range(rep);
}

// Both buffers are each in time order (validation rejects out-of-order frames):
// merge them so the estimator sees one non-decreasing time line. On equal
// stamps the IMU sample goes first (propagate, then update).
void App::process_in_time_order() {
  size_t i = 0;
  size_t u = 0;
  while (i < imu_count_ || u < uwb_count_) {
    const bool take_imu = u >= uwb_count_ || (i < imu_count_ && imu_buf_[i].t_us <= uwb_buf_[u].t_us);
    if (take_imu) {
      ignore_status(nav_.on_imu(imu_buf_[i++]));
    } else {
      handle_range(uwb_buf_[u++]);
    }
  }
}

// GNSS fixes arrive late (their latency) and at a few hertz: each is checked
// and fused after the cycle's IMU and ranges, at its own time of validity.
// Fixes come from the CAN bus (GNSS_Fix*, decoded this cycle) and from the
// board's GnssSource (recordings, a receiver driver), in that order.
void App::drain_gnss(uint64_t now_us) {
#if UWBNAV_GNSS
  for (size_t k = 0; k < can_gnss_count_; ++k) fuse_gnss(can_gnss_[k], now_us);
  can_gnss_count_ = 0;
  if (board_.gnss == nullptr) return;
  GnssFix fix;
  for (size_t n = 0; n < kMaxGnssPerCycle; ++n) {
    const Status s = board_.gnss->poll(now_us, fix);
    if (s == Status::kIoError) {
      ++stats_.gnss.io_errors;
      break;
    }
    if (!ok(s)) break;
    fuse_gnss(fix, now_us);
  }
#else
  static_cast<void>(now_us);
#endif
}

#if UWBNAV_GNSS
void App::fuse_gnss(const GnssFix& fix, uint64_t now_us) {
  ++stats_.gnss.received;
  const Verdict v = validator_.check_gnss(fix, now_us);
  if (!v.accepted) {
    ++stats_.gnss.rejected[static_cast<size_t>(v.reason)];
    return;
  }
  ++stats_.gnss.accepted;
  const GnssReport rep = nav_.on_gnss(fix);
  if (observer_ != nullptr) observer_->on_gnss(rep);
}
#endif

#if UWBNAV_COOP
void App::accept_neighbour(const NeighbourState& s, uint64_t now_us) {
  ++stats_.neighbours.received;
  const Verdict v = validator_.check_neighbour(s, now_us);
  if (!v.accepted) {
    ++stats_.neighbours.rejected[static_cast<size_t>(v.reason)];
    return;
  }
  // The validator has checked what the navigator would refuse.
  if (ok(nav_.on_neighbour_state(s))) {
    ++stats_.neighbours.accepted;
  } else {
    ++stats_.neighbours.rejected[static_cast<size_t>(RejectReason::kOutOfRange)];
  }
}

void App::drain_neighbours(uint64_t now_us) {
  if (board_.neighbours == nullptr) return;
  NeighbourState s;
  for (size_t n = 0; n < kMaxNeighboursPerCycle; ++n) {
    const Status st = board_.neighbours->poll(now_us, s);
    if (st == Status::kIoError) {
      ++stats_.neighbours.io_errors;
      break;
    }
    if (!ok(st)) break;
    accept_neighbour(s, now_us);
  }
}

// This vehicle's state for its neighbours (UWBNAV_Coop*), at its first tag
// antenna: the point their ranges to this vehicle end at.
void App::publish_coop_state() {
  const uint16_t id = can_tx_.coop_vehicle_id();
  if (id == kNoVehicleId) return;
  const Vec3f lever_body_m = board_.site.num_tags > 0 ? board_.site.tags[0].lever_body_m : Vec3f{};
  can_tx_.set_coop_state(can::coop_state_from(last_output_, lever_body_m, id, nav_.cooperative_at(last_output_.t_us)));
}
#endif

void App::tick(uint64_t now_us) {
  last_tick_us_ = now_us;
  if (initialised_) {
    drain_sensors(now_us);
#if UWBNAV_COOP
    drain_neighbours(now_us);
#endif
    process_in_time_order();
    drain_gnss(now_us);
    last_output_ = nav_.output(now_us);
    if (observer_ != nullptr) observer_->on_output(last_output_);
    can_diag_.set_from_stats(stats_);
    can_diag_.resets = last_output_.resets;
#if UWBNAV_COOP
    publish_coop_state();
#endif
    can_tx_.on_cycle(now_us, last_output_, can_diag_, board_.can);
  }
  console_.poll(now_us);
}

}  // namespace uwbnav
