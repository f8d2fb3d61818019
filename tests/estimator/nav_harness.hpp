// Test harness: replays a Recording through the Navigator in sensor-time order
// with an output every 10 ms, and scores the outputs against the truth
// (horizontal RMSE, 2-sigma containment, status counts, finiteness).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "estimator/navigator.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::test {

struct ScoredOutput {
  NavOutput out;
  bool has_truth = false;
  double err_nav_m[3] = {0, 0, 0};  // estimate - truth
};

struct RunScore {
  std::vector<ScoredOutput> outputs;
  size_t n_valid = 0;        // outputs with status valid
  size_t n_scored = 0;       // valid outputs with truth inside [t_from, t_to)
  double rmse_h_m = 0;       // horizontal RMSE over scored outputs
  double max_h_m = 0;
  double inside_2sigma = 0;  // fraction of per-axis (x and y) errors inside 2 sigma
  double mean_sigma_h_m = 0; // mean claimed horizontal sigma sqrt(sx^2 + sy^2) over scored outputs
  bool all_finite = true;
  NavDiagnostics diag;
};

// Defaults with the first fix's redundancy wait off (ekf.init_redundancy_wait 0):
// the first consistent fix, the start that drive-specific bounds were set on.
inline Params first_consistent_fix_params() {
  Params p;
  (void)p.set(ParamId::kEkfInitRedundancyWait, 0.0F);  // 0 lies inside [min, max]: cannot fail
  return p;
}

// Truth position at t_us by linear interpolation; false outside the truth span.
inline bool truth_at(const dataset::Recording& rec, uint64_t t_us, double pos[3]) {
  const auto& tr = rec.truth;
  if (tr.empty() || t_us < tr.front().t_us || t_us > tr.back().t_us) return false;
  auto it = std::lower_bound(tr.begin(), tr.end(), t_us,
                             [](const dataset::TruthRow& r, uint64_t t) { return r.t_us < t; });
  if (it == tr.begin()) {
    for (int i = 0; i < 3; ++i) pos[i] = it->pos_nav_m[i];
    return true;
  }
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double w = b.t_us == a.t_us ? 0.0 : static_cast<double>(t_us - a.t_us) / static_cast<double>(b.t_us - a.t_us);
  for (int i = 0; i < 3; ++i) pos[i] = a.pos_nav_m[i] + w * (b.pos_nav_m[i] - a.pos_nav_m[i]);
  return true;
}

// Without an estimate (mode none) the position is NaN on purpose and the status
// says initialising or invalid; with one, every published number is finite.
inline bool output_well_formed(const NavOutput& o);

inline bool output_finite(const NavOutput& o) {
  bool ok = std::isfinite(o.pos_nav_m.x) && std::isfinite(o.pos_nav_m.y) && std::isfinite(o.pos_nav_m.z) &&
            std::isfinite(o.vel_nav_mps.x) && std::isfinite(o.vel_nav_mps.y) && std::isfinite(o.vel_nav_mps.z) &&
            std::isfinite(o.pos_sigma_m.x) && std::isfinite(o.pos_sigma_m.y) && std::isfinite(o.pos_sigma_m.z) &&
            std::isfinite(o.pos_xy_corr) && std::isfinite(o.heading_rad);
  for (float q : o.q_nav_body) ok = ok && std::isfinite(q);
  return ok;
}

inline bool output_well_formed(const NavOutput& o) {
  if (o.mode == NavMode::kNone) {
    return std::isnan(o.pos_nav_m.x) && std::isnan(o.pos_nav_m.y) && std::isnan(o.pos_nav_m.z) &&
           (o.status == NavStatus::kInitialising || o.status == NavStatus::kInvalid);
  }
  return output_finite(o) && o.pos_sigma_m.x > 0.0F && o.pos_sigma_m.y > 0.0F;
}

// Replays `rec` (IMU and ranges merged by time, output each 10 ms), scoring
// valid outputs in [t_from_us, t_to_us) (0 = whole run). `params` may be
// adjusted by the caller. `reports` receives every RangeReport when not null;
// the recording's GNSS fixes (if any) are fed on arrival, `gnss_reports` gets theirs;
// neighbour states (if any) are fed on arrival before the cycle's ranges.
inline RunScore replay(const dataset::Recording& rec, const Params& params, uint64_t t_from_us = 0,
                       uint64_t t_to_us = UINT64_MAX, std::vector<RangeReport>* reports = nullptr,
                       bool drop_imu = false, std::vector<GnssReport>* gnss_reports = nullptr) {
  RunScore score;
  auto nav = std::make_unique<Navigator>();
  SiteConfig site = rec.site;
  if (drop_imu) site.has_imu = false;
  if (nav->configure(site, params) != Status::kOk) {
    score.all_finite = false;
    return score;
  }
  const std::vector<ImuSample> no_imu;
  const auto& imu = drop_imu ? no_imu : rec.imu;
  size_t i_imu = 0;
  size_t i_uwb = 0;
  size_t i_gnss = 0;
  size_t i_nb = 0;
  uint64_t t0 = UINT64_MAX;
  if (!imu.empty()) t0 = imu.front().t_us;
  if (!rec.uwb.empty()) t0 = std::min(t0, rec.uwb.front().range.t_us);
  uint64_t t_end = 0;
  if (!imu.empty()) t_end = imu.back().t_us;
  if (!rec.uwb.empty()) t_end = std::max(t_end, rec.uwb.back().range.t_us);
  constexpr uint64_t kCycleUs = 10000;
  double sum_sq = 0;
  size_t inside = 0;
  size_t axes = 0;
  double sigma_sum = 0;
  for (uint64_t t_cycle = (t0 / kCycleUs + 1) * kCycleUs; t_cycle <= t_end + kCycleUs; t_cycle += kCycleUs) {
#if UWBNAV_COOP
    // Neighbour states that arrived, before the cycle's ranges (as firmware/app.cpp).
    while (i_nb < rec.neighbours.size() && rec.neighbours[i_nb].rx_t_us <= t_cycle) {
      (void)nav->on_neighbour_state(rec.neighbours[i_nb++]);
    }
#else
    static_cast<void>(i_nb);
#endif
    while (true) {
      const bool imu_next = i_imu < imu.size() && imu[i_imu].t_us <= t_cycle;
      const bool uwb_next = i_uwb < rec.uwb.size() && rec.uwb[i_uwb].range.t_us <= t_cycle;
      if (!imu_next && !uwb_next) break;
      if (imu_next && (!uwb_next || imu[i_imu].t_us <= rec.uwb[i_uwb].range.t_us)) {
        (void)nav->on_imu(imu[i_imu++]);
      } else {
        const RangeReport r = nav->on_range(rec.uwb[i_uwb++].range);
        if (reports != nullptr) reports->push_back(r);
      }
    }
    // GNSS fixes after the cycle's IMU and ranges, when they arrive (as firmware/app.cpp).
    while (i_gnss < rec.gnss.size() && rec.gnss[i_gnss].rx_t_us <= t_cycle) {
      const GnssReport g = nav->on_gnss(rec.gnss[i_gnss++]);
      if (gnss_reports != nullptr) gnss_reports->push_back(g);
    }
    ScoredOutput so;
    so.out = nav->output(t_cycle);
    if (!output_well_formed(so.out)) score.all_finite = false;
    double truth[3];
    if (truth_at(rec, t_cycle, truth)) {
      so.has_truth = true;
      so.err_nav_m[0] = static_cast<double>(so.out.pos_nav_m.x) - truth[0];
      so.err_nav_m[1] = static_cast<double>(so.out.pos_nav_m.y) - truth[1];
      so.err_nav_m[2] = static_cast<double>(so.out.pos_nav_m.z) - truth[2];
    }
    if (so.out.status == NavStatus::kValid) {
      ++score.n_valid;
      if (so.has_truth && t_cycle >= t_from_us && t_cycle < t_to_us) {
        ++score.n_scored;
        const double eh2 = so.err_nav_m[0] * so.err_nav_m[0] + so.err_nav_m[1] * so.err_nav_m[1];
        sum_sq += eh2;
        score.max_h_m = std::max(score.max_h_m, std::sqrt(eh2));
        const double sx = static_cast<double>(so.out.pos_sigma_m.x);
        const double sy = static_cast<double>(so.out.pos_sigma_m.y);
        inside += (std::fabs(so.err_nav_m[0]) <= 2 * sx) + (std::fabs(so.err_nav_m[1]) <= 2 * sy);
        sigma_sum += std::sqrt(sx * sx + sy * sy);
        axes += 2;
      }
    }
    score.outputs.push_back(so);
  }
  if (score.n_scored > 0) {
    score.rmse_h_m = std::sqrt(sum_sq / static_cast<double>(score.n_scored));
    score.mean_sigma_h_m = sigma_sum / static_cast<double>(score.n_scored);
  }
  if (axes > 0) score.inside_2sigma = static_cast<double>(inside) / static_cast<double>(axes);
  score.diag = nav->diagnostics();
  return score;
}

}  // namespace uwbnav::test
