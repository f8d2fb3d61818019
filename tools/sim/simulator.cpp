// Simulator core: samples the truth trajectory, applies the MEMS IMU error
// model (seed 000 Table 1), the UWB ranging/NLOS/channel models, the GNSS
// receiver model and the neighbour vehicles (broadcast states, inter-vehicle
// ranges), and fills a format v1 Recording.
#include "tools/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "tools/sim/coop.hpp"
#include "tools/sim/rng.hpp"
#include "tools/sim/trajectory.hpp"

namespace uwbnav::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Independent random streams: changing one model never shifts another's draws.
constexpr uint64_t kStreamImu = 0x494D55ULL;        // "IMU"
constexpr uint64_t kStreamSlot = 0x534C4F54ULL;     // "SLOT": per range slot
constexpr uint64_t kStreamEpisode = 0x45504953ULL;  // "EPIS": NLOS episode biases
constexpr uint64_t kStreamProtocol = 0x50524F54ULL; // "PROT"
constexpr uint64_t kStreamVibration = 0x56494252ULL; // "VIBR": IMU vibration
constexpr uint64_t kStreamSurvey = 0x53555256ULL;   // "SURV": anchor survey errors
constexpr uint64_t kStreamOffset = 0x4F464653ULL;   // "OFFS": range offsets and scale errors
constexpr uint64_t kStreamRenewal = 0x52454E57ULL;  // "RENW": random NLOS episodes per pair
constexpr uint64_t kStreamBurst = 0x42525354ULL;    // "BRST": Gilbert-Elliott state per pair
constexpr uint64_t kStreamBlock = 0x424C434BULL;    // "BLCK": anchor blockage schedule
constexpr uint64_t kStreamSlot2 = 0x534C5432ULL;    // "SLT2": per-slot draws of the episode model
constexpr uint64_t kStreamGnss = 0x474E5353ULL;     // "GNSS": receiver errors, latency, multipath windows
constexpr uint64_t kStreamCoop = 0x434F4F50ULL;     // "COOP": neighbour broadcast errors and latencies per vehicle
constexpr uint64_t kStreamCoopSlot = 0x43534C54ULL; // "CSLT": per inter-vehicle range slot
constexpr uint64_t kStreamCoopBias = 0x43424953ULL; // "CBIS": bias of a range blocked by a third vehicle

// One uwb.csv row (anchor or vehicle tag) with the DW1000-like channel
// diagnostics when the scenario has them: log-distance path loss; blocked
// paths lose nlos_extra_loss_db and show a larger total-minus-first-path gap
// (folded normal).
dataset::UwbRow range_row(uint64_t t_us, uint16_t id, uint8_t tag_id, double range_m, RangeCause cause,
                          bool geometric_nlos, double true_range_m, bool diagnostics, const ChannelConfig& ch,
                          double n_shadow, double n_gap) {
  dataset::UwbRow row;
  row.range.t_us = t_us;
  row.range.anchor_id = id;
  row.range.tag_id = tag_id;
  row.range.range_m = static_cast<float>(range_m);
  row.nlos_label = cause == RangeCause::kLos ? 0 : 1;
  if (diagnostics) {
    const bool weak_first_path = geometric_nlos || cause == RangeCause::kOutlier;
    double rx = ch.rx_power_1m_dbm - 10.0 * ch.path_loss_exponent * std::log10(std::max(true_range_m, 0.3)) +
                ch.shadowing_sigma_db * n_shadow;
    if (geometric_nlos) rx -= ch.nlos_extra_loss_db;
    const double gap = weak_first_path ? std::fabs(ch.nlos_gap_mean_db + ch.nlos_gap_sigma_db * n_gap)
                                       : std::fabs(ch.los_gap_mean_db + ch.los_gap_sigma_db * n_gap);
    row.range.rx_power_dbm = static_cast<float>(rx);
    row.range.fp_power_dbm = static_cast<float>(rx - gap);
  }
  return row;
}

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// Shortest decimal text that reads back as the same float.
std::string fmt_float(float v) {
  char buf[64];
  for (int digits = 6; digits <= 9; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, static_cast<double>(v));
    if (std::strtof(buf, nullptr) == v) break;
  }
  return buf;
}

Vec3f to_vec3f(const double* v) {
  return Vec3f{static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

double quantise(double x, double lsb) { return lsb > 0.0 ? lsb * std::round(x / lsb) : x; }

double saturate(double x, double limit) { return std::min(std::max(x, -limit), limit); }

// NLOS episode state of one (tag, anchor) pair: a bias is drawn when a blockage
// starts and kept (with range-to-range jitter) while it lasts.
struct Episode {
  bool blocked = false;
  double bias_m = 0.0;
};

void fill_meta(const Scenario& sc, const SimOptions& opt, dataset::Recording& rec) {
  rec.meta["name"] = sc.name;
  rec.meta["description"] = sc.description;
  rec.meta["source"] = "uwbnav-sim";
  rec.meta["platform"] = sc.platform;
  rec.meta["gravity_mps2"] = fmt_float(static_cast<float>(sc.gravity_mps2));
  rec.meta["uwb_sigma_m"] = fmt(sc.uwb.sigma_m);
  rec.meta["imu_rate_hz"] = fmt(sc.imu.rate_hz);
  rec.meta["uwb_rate_hz"] = fmt(sc.uwb.rate_hz);
  rec.meta["seed"] = std::to_string(opt.seed);
  if (sc.uwb.schedule != UwbSchedule::kRoundRobin) {
    rec.meta["sim_uwb_schedule"] = sc.uwb.schedule == UwbSchedule::kFrame ? "frame" : "per_anchor";
  }
  if (!sc.uwb.outages.empty()) {
    std::string list;
    for (const Outage& o : sc.uwb.outages) {
      if (!list.empty()) list += ' ';
      list += "[" + fmt(o.start_s) + "," + fmt(o.end_s) + ")";
    }
    rec.meta["sim_outages_s"] = list;
  }
  if (opt.ideal_imu) rec.meta["sim_ideal_imu"] = "1";
  if (opt.ideal_uwb) rec.meta["sim_ideal_uwb"] = "1";
  if (sc.uwb.max_range_m > 0.0) rec.meta["sim_uwb_max_range_m"] = fmt(sc.uwb.max_range_m);
  if (sc.platform == "ground" && sc.vehicle.pitch_gain_deg_per_mps2 != 0.0) {
    rec.meta["sim_pitch_gain_deg_per_mps2"] = fmt(sc.vehicle.pitch_gain_deg_per_mps2);
  }
  if (!sc.gnss.enabled) return;
  const GnssConfig& g = sc.gnss;
  // The antenna lever is site configuration (meta.ini gnss_lever_m, docs/dataset-format.md);
  // the rest are simulator facts for evaluation.
  rec.meta["gnss_lever_m"] = fmt_float(static_cast<float>(g.lever_body_m[0])) + "," +
                             fmt_float(static_cast<float>(g.lever_body_m[1])) + "," +
                             fmt_float(static_cast<float>(g.lever_body_m[2]));
  rec.meta["sim_gnss_rate_hz"] = fmt(g.rate_hz);
  rec.meta["sim_gnss_latency_ms"] = fmt(g.latency_ms);
  rec.meta["sim_gnss_latency_jitter_ms"] = fmt(g.latency_jitter_ms);
  rec.meta["sim_gnss_sigma_h_m"] = fmt(g.sigma_h_m);
  rec.meta["sim_gnss_sigma_v_m"] = fmt(g.sigma_v_m);
  rec.meta["sim_gnss_tau_s"] = fmt(g.tau_s);
  rec.meta["sim_gnss_sigma_white_m"] = fmt(g.sigma_white_m);
  rec.meta["sim_gnss_claim_ratio"] = fmt(g.claim_ratio);
  if (!g.windows.empty()) {
    std::string list;
    for (const GnssWindow& w : g.windows) {
      if (!list.empty()) list += ' ';
      list += "[" + fmt(w.start_s) + "," + fmt(w.end_s) + "):" +
              (w.kind == GnssWindowKind::kBlocked ? "blocked" : "multipath");
    }
    rec.meta["sim_gnss_windows_s"] = list;
  }
  if (g.multipath_bias_m > 0.0) rec.meta["sim_gnss_multipath_bias_m"] = fmt(g.multipath_bias_m);
}

// Simulator facts of the neighbour vehicles (evaluation only).
void fill_meta_coop(const Scenario& sc, dataset::Recording& rec) {
  const CoopConfig& c = sc.coop;
  if (c.vehicles.empty()) return;
  std::string ids;
  for (const NeighbourDef& n : c.vehicles) {
    ids += (ids.empty() ? "" : ",") + std::to_string(n.id);
    std::string v = n.motion == NeighbourMotion::kOffset
                        ? "offset " + fmt(n.offset_m[0]) + " " + fmt(n.offset_m[1])
                        : "route " + fmt(n.route.start_nav_m[0]) + " " + fmt(n.route.start_nav_m[1]) + " " +
                              fmt(n.route.start_nav_m[2]) + " " + fmt(n.route.start_heading_deg);
    v += ", tag " + fmt(n.tag_lever_body_m[0]) + " " + fmt(n.tag_lever_body_m[1]) + " " + fmt(n.tag_lever_body_m[2]);
    v += ", sigma " + fmt(n.sigma_m[0]) + " " + fmt(n.sigma_m[1]) + " " + fmt(n.sigma_m[2]) + ", tau " + fmt(n.tau_s);
    rec.meta["sim_coop_vehicle_" + std::to_string(n.id)] = v;
  }
  rec.meta["sim_coop_vehicles"] = ids;
  rec.meta["sim_coop_rate_hz"] = fmt(c.rate_hz);
  rec.meta["sim_coop_latency_ms"] = fmt(c.latency_ms);
  rec.meta["sim_coop_latency_jitter_ms"] = fmt(c.latency_jitter_ms);
  rec.meta["sim_coop_range_rate_hz"] = fmt(c.range_rate_hz);
  rec.meta["sim_coop_box_m"] = fmt(c.box_m[0]) + " " + fmt(c.box_m[1]) + " " + fmt(c.box_m[2]);
  rec.meta["sim_coop_nlos_bias_m"] = fmt(c.nlos_bias_min_m) + " " + fmt(c.nlos_bias_max_m);
}

// Simulator facts of the new error models (evaluation only; the firmware never reads meta.ini).
void fill_meta_errors(const Scenario& sc, const SimOptions& opt, const SimOutput& out, dataset::Recording& rec) {
  if (opt.ideal_uwb) return;
  if (sc.site.survey_sigma_m > 0.0) {
    for (const AnchorDef& a : sc.anchors) {
      rec.meta["sim_anchor_true_" + std::to_string(a.id)] =
          fmt(a.pos_nav_m[0]) + " " + fmt(a.pos_nav_m[1]) + " " + fmt(a.pos_nav_m[2]);
    }
  }
  for (const PairError& e : out.pair_errors) {
    const std::string key = std::to_string(e.anchor_id) + "_" + std::to_string(e.tag_id);
    if (e.offset_m != 0.0) rec.meta["sim_range_offset_m_" + key] = fmt(e.offset_m);
    if (e.scale != 0.0) rec.meta["sim_range_scale_" + key] = fmt(e.scale);
  }
  if (!out.blockages.empty()) {
    std::string list;
    for (const Blockage& b : out.blockages) {
      if (!list.empty()) list += ' ';
      list += "[" + fmt(b.start_s) + "," + fmt(b.end_s) + "):";
      for (size_t i = 0; i < b.anchor_ids.size(); ++i) list += (i ? "," : "") + std::to_string(b.anchor_ids[i]);
    }
    rec.meta["sim_blockages_s"] = list;
  }
  if (sc.nlos.episode_share > 0.0) rec.meta["sim_episode_share"] = fmt(sc.nlos.episode_share);
}

// anchors.csv positions: the truth plus N(0, survey_sigma_m) per axis, rounded to float.
std::vector<AnchorDef> survey_anchors(const Scenario& sc, const SimOptions& opt) {
  std::vector<AnchorDef> out = sc.anchors;
  if (opt.ideal_uwb || sc.site.survey_sigma_m <= 0.0) return out;
  Rng rng(mix_seed(opt.seed, kStreamSurvey));
  for (AnchorDef& a : out) {
    for (double& x : a.pos_nav_m) {
      x = static_cast<double>(static_cast<float>(x + sc.site.survey_sigma_m * rng.normal()));
    }
  }
  return out;
}

// Offsets and scale errors per (tag, anchor), tag-major: drawn N(0, sigma)
// per anchor, per tag and per pair; explicit values replace the draws.
std::vector<PairError> draw_pair_errors(const Scenario& sc, const SimOptions& opt) {
  const UwbConfig& u = sc.uwb;
  std::vector<PairError> out;
  out.reserve(sc.tags.size() * sc.anchors.size());
  Rng ra(mix_seed(opt.seed, kStreamOffset, 1));
  Rng rt(mix_seed(opt.seed, kStreamOffset, 2));
  Rng rp(mix_seed(opt.seed, kStreamOffset, 3));
  Rng rs(mix_seed(opt.seed, kStreamOffset, 4));
  std::vector<double> anchor_off(sc.anchors.size());
  std::vector<double> tag_off(sc.tags.size());
  for (size_t a = 0; a < sc.anchors.size(); ++a) {
    anchor_off[a] = u.anchor_offset_sigma_m * ra.normal();
    for (const RangeOffset& o : u.anchor_offsets) {
      if (o.anchor_id == sc.anchors[a].id) anchor_off[a] = o.offset_m;
    }
  }
  for (size_t j = 0; j < sc.tags.size(); ++j) {
    tag_off[j] = u.tag_offset_sigma_m * rt.normal();
    for (const RangeOffset& o : u.tag_offsets) {
      if (o.tag_id == sc.tags[j].id) tag_off[j] = o.offset_m;
    }
  }
  for (size_t j = 0; j < sc.tags.size(); ++j) {
    for (size_t a = 0; a < sc.anchors.size(); ++a) {
      PairError e;
      e.anchor_id = sc.anchors[a].id;
      e.tag_id = sc.tags[j].id;
      double pair = u.pair_offset_sigma_m * rp.normal();
      for (const RangeOffset& o : u.pair_offsets) {
        if (o.anchor_id == e.anchor_id && o.tag_id == e.tag_id) pair = o.offset_m;
      }
      e.offset_m = opt.ideal_uwb ? 0.0 : anchor_off[a] + tag_off[j] + pair;
      const double scale_pct = u.scale_common_pct + u.scale_pair_sigma_pct * rs.normal();
      e.scale = opt.ideal_uwb ? 0.0 : 0.01 * scale_pct;
      out.push_back(e);
    }
  }
  return out;
}

// Blockage schedule: gap U[gap_min, gap_max], then block_anchors distinct random
// anchors silent for U[block_min, block_max], repeated to the end of the run.
std::vector<Blockage> draw_blockages(const Scenario& sc, const SimOptions& opt) {
  std::vector<Blockage> out;
  const UwbConfig& u = sc.uwb;
  if (u.block_anchors == 0) return out;
  Rng rng(mix_seed(opt.seed, kStreamBlock));
  double t = rng.uniform(u.block_gap_min_s, u.block_gap_max_s);
  while (t < sc.duration_s) {
    std::vector<size_t> idx(sc.anchors.size());
    for (size_t i = 0; i < idx.size(); ++i) idx[i] = i;
    Blockage b;
    for (size_t m = 0; m < u.block_anchors; ++m) {
      const size_t pick = m + static_cast<size_t>(rng.below(idx.size() - m));
      std::swap(idx[m], idx[pick]);
      b.anchor_ids.push_back(sc.anchors[idx[m]].id);
    }
    b.start_s = t;
    b.end_s = t + rng.uniform(u.block_min_s, u.block_max_s);
    out.push_back(b);
    t = b.end_s + rng.uniform(u.block_gap_min_s, u.block_gap_max_s);
  }
  return out;
}

// Random NLOS episodes of one pair: alternating LOS stretches and NLOS episodes
// (alternating renewal process). The NLOS mean length is episode_mean_s, the
// LOS mean episode_mean_s (1 - share) / share, so the long-run NLOS share of
// time is `share`; the process starts in NLOS with probability `share`.
struct EpisodeInterval {
  uint64_t start_us = 0;
  uint64_t end_us = 0;
  double bias_m = 0.0;  // episode bias [m]
};

std::vector<EpisodeInterval> draw_episodes(const NlosConfig& nl, uint64_t seed, uint64_t pair, uint64_t dur_us) {
  std::vector<EpisodeInterval> out;
  if (nl.episode_share <= 0.0) return out;
  Rng rng(mix_seed(seed, kStreamRenewal, pair));
  const double mean_nlos = nl.episode_mean_s;
  const double mean_los = nl.episode_mean_s * (1.0 - nl.episode_share) / nl.episode_share;
  const auto length = [&](double mean) {
    return nl.episode_length_law == RandomLaw::kExponential ? rng.exponential(mean)
                                                            : rng.lognormal_mean(mean, nl.episode_length_shape);
  };
  bool in_nlos = rng.uniform() < nl.episode_share;
  double t = 0.0;
  const double end_s = static_cast<double>(dur_us) * 1e-6;
  while (t < end_s) {
    const double len = length(in_nlos ? mean_nlos : mean_los);
    if (in_nlos) {
      EpisodeInterval e;
      e.start_us = static_cast<uint64_t>(std::llround(t * 1e6));
      e.end_us = static_cast<uint64_t>(std::llround((t + len) * 1e6));
      e.bias_m = nl.episode_bias_law == RandomLaw::kExponential ? rng.exponential(nl.episode_bias_mean_m)
                                                                 : rng.lognormal_mean(nl.episode_bias_mean_m, nl.bias_shape);
      out.push_back(e);
    }
    t += len;
    in_nlos = !in_nlos;
  }
  return out;
}

Status fill_site(const Scenario& sc, const std::vector<AnchorDef>& anchors, SiteConfig& site, std::string* error) {
  site = SiteConfig{};
  for (const AnchorDef& a : anchors) {
    if (!ok(site.add_anchor(a.id, to_vec3f(a.pos_nav_m)))) {
      if (error != nullptr) *error = "cannot add anchor " + std::to_string(a.id);
      return Status::kInvalidArgument;
    }
  }
  for (const TagDef& t : sc.tags) {
    if (!ok(site.add_tag(t.id, to_vec3f(t.lever_body_m)))) {
      if (error != nullptr) *error = "cannot add tag " + std::to_string(t.id);
      return Status::kInvalidArgument;
    }
  }
  site.platform = sc.platform == "air" ? Platform::kAir : Platform::kGround;
  site.gravity_mps2 = static_cast<float>(sc.gravity_mps2);
  site.has_imu = sc.imu.enabled;
  if (sc.gnss.enabled) site.gnss_lever_body_m = to_vec3f(sc.gnss.lever_body_m);
  return Status::kOk;
}

// Vibration noise of three axes: white, or a second-order resonator driven by
// white noise (AR(2) with poles r e^{+-j theta}, r = exp(-pi B dt), theta =
// 2 pi f dt) scaled to the requested RMS by its stationary variance
// gamma0 = s^2 (1 - a2) / ((1 + a2) ((1 - a2)^2 - a1^2)) for x_k = a1 x_k-1 + a2 x_k-2 + e_k.
class Vibration {
 public:
  Vibration(double rms, const ImuConfig& c, double dt_s, uint64_t seed) : rng_(seed), rms_(rms) {
    if (rms <= 0.0 || c.vibration_hz <= 0.0) {
      drive_ = rms;
      return;
    }
    resonant_ = true;
    const double r = std::exp(-kPi * c.vibration_bandwidth_hz * dt_s);
    a1_ = 2.0 * r * std::cos(2.0 * kPi * c.vibration_hz * dt_s);
    a2_ = -r * r;
    const double gain = (1.0 - a2_) / ((1.0 + a2_) * ((1.0 - a2_) * (1.0 - a2_) - a1_ * a1_));
    drive_ = rms / std::sqrt(gain);
    // Settle to the stationary state before t = 0 (many time constants 1 / (pi B)).
    const int settle = static_cast<int>(10.0 / (kPi * c.vibration_bandwidth_hz * dt_s)) + 1;
    double dummy[3] = {0, 0, 0};
    for (int k = 0; k < settle; ++k) add(dummy);
  }
  void add(double v[3]) {
    if (rms_ <= 0.0) return;
    for (int i = 0; i < 3; ++i) {
      const double e = drive_ * rng_.normal();
      if (!resonant_) {
        v[i] += e;
        continue;
      }
      const double x = a1_ * x1_[i] + a2_ * x2_[i] + e;
      x2_[i] = x1_[i];
      x1_[i] = x;
      v[i] += x;
    }
  }

 private:
  Rng rng_;
  double rms_ = 0.0;
  bool resonant_ = false;
  double drive_ = 0.0;
  double a1_ = 0.0, a2_ = 0.0;
  double x1_[3] = {0, 0, 0};
  double x2_[3] = {0, 0, 0};
};

// IMU at rate_hz with turn-on biases, bias random walks, white noise,
// saturation and quantisation (seed 000 Table 1 figures by default).
void simulate_imu(const Scenario& sc, const SimOptions& opt, const Trajectory& traj, uint64_t dur_us,
                  SimOutput& out) {
  const uint64_t period_us = static_cast<uint64_t>(std::llround(1e6 / sc.imu.rate_hz));
  const size_t n = static_cast<size_t>((dur_us + period_us - 1) / period_us);
  const double dt_s = static_cast<double>(period_us) * 1e-6;
  const double g = sc.gravity_mps2;
  const ImuConfig& c = sc.imu;
  const bool noisy = !opt.ideal_imu;

  Rng rng(mix_seed(opt.seed, kStreamImu));
  double gyro_bias[3] = {0, 0, 0};
  double accel_bias[3] = {0, 0, 0};
  for (double& b : gyro_bias) b = noisy ? c.gyro_bias_sigma_dps * kDeg * rng.normal() : 0.0;
  for (double& b : accel_bias) b = noisy ? c.accel_bias_sigma_mg * 1e-3 * g * rng.normal() : 0.0;
  // White noise per sample: density * sqrt(rate). ARW [deg/sqrt(h)] / 60 = [deg/s/sqrt(Hz)].
  const double gyro_sigma = c.gyro_arw_dps_per_sqrt_h / 60.0 * kDeg * std::sqrt(c.rate_hz);
  const double accel_sigma = c.accel_noise_ug_per_sqrt_hz * 1e-6 * g * std::sqrt(sc.imu.rate_hz);
  const double gyro_rw = c.gyro_bias_rw_dps_per_sqrt_s * kDeg * std::sqrt(dt_s);
  const double accel_rw = c.accel_bias_rw_mps2_per_sqrt_s * std::sqrt(dt_s);
  const double gyro_limit = c.gyro_range_dps * kDeg;
  const double accel_limit = c.accel_range_g * g;
  const double gyro_lsb = noisy ? c.gyro_lsb_dps * kDeg : 0.0;
  const double accel_lsb = noisy ? c.accel_lsb_mg * 1e-3 * g : 0.0;
  Vibration vib_gyro(c.vibration_gyro_dps * kDeg, c, dt_s, mix_seed(opt.seed, kStreamVibration, 1));
  Vibration vib_accel(c.vibration_accel_mps2, c, dt_s, mix_seed(opt.seed, kStreamVibration, 2));

  out.truth.reserve(n);
  out.rec.truth.reserve(n);
  if (c.enabled) out.rec.imu.reserve(n);
  for (size_t k = 0; k < n; ++k) {
    const uint64_t t_us = k * period_us;
    const KinState st = traj.at(t_us);
    TruthState ts;
    ts.t_us = t_us;
    for (int i = 0; i < 3; ++i) {
      ts.pos_nav_m[i] = st.pos_nav_m[i];
      ts.vel_nav_mps[i] = st.vel_nav_mps[i];
      ts.acc_nav_mps2[i] = st.acc_nav_mps2[i];
      ts.gyro_body_radps[i] = st.gyro_body_radps[i];
      ts.accel_body_mps2[i] = st.accel_body_mps2[i];
    }
    ts.q_nav_body[0] = st.q_nav_body.w();
    ts.q_nav_body[1] = st.q_nav_body.x();
    ts.q_nav_body[2] = st.q_nav_body.y();
    ts.q_nav_body[3] = st.q_nav_body.z();
    out.truth.push_back(ts);

    dataset::TruthRow row;
    row.t_us = t_us;
    for (int i = 0; i < 3; ++i) row.pos_nav_m[i] = ts.pos_nav_m[i];
    row.has_attitude = true;
    for (int i = 0; i < 4; ++i) row.q_nav_body[i] = ts.q_nav_body[i];
    out.rec.truth.push_back(row);

    if (!c.enabled) continue;
    double gyro[3];
    double accel[3];
    for (int i = 0; i < 3; ++i) {
      gyro[i] = st.gyro_body_radps[i];
      accel[i] = st.accel_body_mps2[i];
    }
    if (noisy) {
      for (int i = 0; i < 3; ++i) gyro[i] += gyro_bias[i] + gyro_sigma * rng.normal();
      for (int i = 0; i < 3; ++i) accel[i] += accel_bias[i] + accel_sigma * rng.normal();
      for (double& b : gyro_bias) b += gyro_rw * rng.normal();
      for (double& b : accel_bias) b += accel_rw * rng.normal();
      vib_gyro.add(gyro);
      vib_accel.add(accel);
    }
    ImuSample s;
    s.t_us = t_us;
    s.gyro_body_radps = Vec3f{static_cast<float>(quantise(saturate(gyro[0], gyro_limit), gyro_lsb)),
                              static_cast<float>(quantise(saturate(gyro[1], gyro_limit), gyro_lsb)),
                              static_cast<float>(quantise(saturate(gyro[2], gyro_limit), gyro_lsb))};
    s.accel_body_mps2 = Vec3f{static_cast<float>(quantise(saturate(accel[0], accel_limit), accel_lsb)),
                              static_cast<float>(quantise(saturate(accel[1], accel_limit), accel_lsb)),
                              static_cast<float>(quantise(saturate(accel[2], accel_limit), accel_lsb))};
    out.rec.imu.push_back(s);
  }
}

bool in_outage(const Scenario& sc, uint64_t t_us) {
  const double t_s = static_cast<double>(t_us) * 1e-6;
  for (const Outage& o : sc.uwb.outages) {
    if (t_s >= o.start_s && t_s < o.end_s) return true;
  }
  return false;
}

// True when the vehicle body shadows the anchor: the direction to the anchor,
// in the body frame, points below the roof antenna and rearward within the cone.
bool body_blocks(const Eigen::Vector3d& dir_body, double cone_deg) {
  if (dir_body.z() >= 0.0) return false;
  const double horizontal = std::hypot(dir_body.x(), dir_body.y());
  if (horizontal <= 0.0) return true;
  const double bearing_from_rear = std::atan2(std::fabs(dir_body.y()), -dir_body.x());
  return bearing_from_rear <= cone_deg * kDeg;
}

// Calls visit(t_us, tag index, anchor index, slot id) for every range slot in
// time order. round_robin: tag j's slot k at offset + k / rate + j / (rate n_tags)
// ranges anchor (k + j) mod n_anchors, slot id k n_tags + j; per_anchor: the same
// at rate x n_anchors (stamps rounded to the microsecond); frame: every tag
// ranges every anchor at offset + k / rate, slot id (k n_tags + j) n_anchors + a.
template <typename Visit>
void for_each_slot(const Scenario& sc, uint64_t dur_us, Visit visit) {
  const size_t n_anchors = sc.anchors.size();
  const size_t n_tags = sc.tags.size();
  const uint64_t offset_us = static_cast<uint64_t>(std::llround(sc.uwb.offset_ms * 1e3));
  if (sc.uwb.schedule == UwbSchedule::kRoundRobin) {
    const uint64_t period_us = static_cast<uint64_t>(std::llround(1e6 / sc.uwb.rate_hz));
    const uint64_t tag_step_us = period_us / n_tags;
    for (uint64_t k = 0;; ++k) {
      const uint64_t slot_t0 = offset_us + k * period_us;
      if (slot_t0 >= dur_us) return;
      for (size_t j = 0; j < n_tags; ++j) {
        const uint64_t t_us = slot_t0 + j * tag_step_us;
        if (t_us >= dur_us) break;
        visit(t_us, j, static_cast<size_t>((k + j) % n_anchors), k * n_tags + j);
      }
    }
  }
  if (sc.uwb.schedule == UwbSchedule::kPerAnchor) {
    const double period_us = 1e6 / (sc.uwb.rate_hz * static_cast<double>(n_anchors));
    for (uint64_t k = 0;; ++k) {
      const uint64_t slot_t0 = offset_us + static_cast<uint64_t>(std::llround(static_cast<double>(k) * period_us));
      if (slot_t0 >= dur_us) return;
      for (size_t j = 0; j < n_tags; ++j) {
        const uint64_t t_us =
            slot_t0 + static_cast<uint64_t>(std::llround(static_cast<double>(j) * period_us / static_cast<double>(n_tags)));
        if (t_us >= dur_us) break;
        visit(t_us, j, static_cast<size_t>((k + j) % n_anchors), k * n_tags + j);
      }
    }
  }
  const double period_us = 1e6 / sc.uwb.rate_hz;
  for (uint64_t k = 0;; ++k) {
    const uint64_t t_us = offset_us + static_cast<uint64_t>(std::llround(static_cast<double>(k) * period_us));
    if (t_us >= dur_us) return;
    for (size_t j = 0; j < n_tags; ++j) {
      for (size_t a = 0; a < n_anchors; ++a) visit(t_us, j, a, (k * n_tags + j) * n_anchors + a);
    }
  }
}

// Gilbert-Elliott two-state loss of one pair, stepped once per slot of that
// pair: the bad state loses every range, mean stay 1 / r = burst_mean_len, and
// p = r share / (1 - share) so the long-run bad share is `share`.
struct BurstState {
  explicit BurstState(uint64_t seed) : rng(seed) {}
  Rng rng;
  bool bad = false;
  bool started = false;
  bool step(double share, double mean_len) {
    const double r = 1.0 / mean_len;
    const double p = r * share / (1.0 - share);
    if (!started) {
      started = true;
      bad = rng.uniform() < share;
    } else {
      const double u = rng.uniform();
      bad = bad ? u >= r : u < p;
    }
    return bad;
  }
};

// UWB ranges on the slot schedule (for_each_slot), stamped at the ranging
// instant: scale error and offsets, noise, geometry NLOS, random NLOS episodes,
// outliers, packet and burst loss, outages, anchor blockages, quantisation and
// DW1000-style channel diagnostics.
void simulate_uwb(const Scenario& sc, const SimOptions& opt, const Trajectory& traj, uint64_t dur_us,
                  SimOutput& out) {
  const size_t n_anchors = sc.anchors.size();
  const size_t n_tags = sc.tags.size();
  const NlosConfig& nl = sc.nlos;
  const ChannelConfig& ch = sc.channel;
  const bool noisy = !opt.ideal_uwb;
  const double packet_loss = noisy ? sc.uwb.packet_loss : 0.0;
  const double burst_loss = noisy ? sc.uwb.burst_loss : 0.0;
  const double sigma = noisy ? sc.uwb.sigma_m : 0.0;
  const double outlier_prob = noisy ? nl.outlier_prob : 0.0;
  const double lsb = noisy ? sc.uwb.range_lsb_m : 0.0;
  const double ln_out_min = std::log(nl.outlier_min_m);
  const double ln_out_max = std::log(nl.outlier_max_m);

  std::vector<Episode> box_ep(n_tags * n_anchors);
  std::vector<Episode> body_ep(n_tags * n_anchors);
  std::vector<std::vector<EpisodeInterval>> episodes(n_tags * n_anchors);
  std::vector<size_t> episode_cursor(n_tags * n_anchors, 0);
  std::vector<BurstState> bursts;
  bursts.reserve(n_tags * n_anchors);
  for (size_t p = 0; p < n_tags * n_anchors; ++p) {
    if (noisy) episodes[p] = draw_episodes(nl, opt.seed, p, dur_us);
    bursts.emplace_back(mix_seed(opt.seed, kStreamBurst, p));
  }
  // Ranges per second over all tags (round-robin: rate per tag; otherwise per anchor and tag).
  const double slots_per_s = sc.uwb.rate_hz * static_cast<double>(
                                                  sc.uwb.schedule == UwbSchedule::kRoundRobin ? n_tags : n_anchors * n_tags);
  out.rec.uwb.reserve(static_cast<size_t>(static_cast<double>(dur_us) * 1e-6 * slots_per_s) + n_tags * n_anchors);
  out.range_truth.reserve(out.rec.uwb.capacity());

  const auto blocked = [&](size_t a, uint64_t t_us) {
    const double t_s = static_cast<double>(t_us) * 1e-6;
    for (const Blockage& b : out.blockages) {
      if (t_s < b.start_s || t_s >= b.end_s) continue;
      for (uint16_t id : b.anchor_ids) {
        if (id == sc.anchors[a].id) return true;
      }
    }
    return false;
  };

  uint64_t state_t_us = UINT64_MAX;
  KinState state;
  for_each_slot(sc, dur_us, [&](uint64_t t_us, size_t j, size_t a, uint64_t slot_id) {
    const AnchorDef& anchor = sc.anchors[a];
    const TagDef& tag = sc.tags[j];
    const size_t pair = j * n_anchors + a;

    // Every slot draws the same numbers in the same order, used or not.
    Rng r(mix_seed(opt.seed, kStreamSlot, slot_id));
    const double u_loss = r.uniform();
    const double n_range = r.normal();
    const double u_outlier = r.uniform();
    const double u_out_mag = r.uniform();
    const double u_out_sign = r.uniform();
    const double n_box_jitter = r.normal();
    const double n_box_extra = r.normal();
    const double n_body_jitter = r.normal();
    const double n_body_extra = r.normal();
    const double n_shadow = r.normal();
    const double n_gap = r.normal();

    // Frames range every pair at one instant: evaluate the truth once per instant.
    if (t_us != state_t_us) {
      state = traj.at(t_us);
      state_t_us = t_us;
    }
    const KinState& st = state;
    const Eigen::Vector3d lever(tag.lever_body_m[0], tag.lever_body_m[1], tag.lever_body_m[2]);
    const Eigen::Vector3d tag_nav = st.pos_nav_m + st.R_nav_body * lever;
    const Eigen::Vector3d anchor_nav(anchor.pos_nav_m[0], anchor.pos_nav_m[1], anchor.pos_nav_m[2]);
    const double true_range = (anchor_nav - tag_nav).norm();

    bool box_blocked = false;
    for (const Box& b : nl.boxes) box_blocked = box_blocked || segment_hits_box(tag_nav, anchor_nav, b);
    const bool body_blocked =
        nl.body_block && body_blocks(st.R_nav_body.transpose() * (anchor_nav - tag_nav), nl.body_cone_deg);

    // Episode biases: drawn when a blockage starts (seed 000 §2.1 cites a
    // positive NLOS bias; heavy tail by a log-normal law).
    Episode& be = box_ep[pair];
    Episode& de = body_ep[pair];
    if (box_blocked && !be.blocked) {
      Rng re(mix_seed(opt.seed, kStreamEpisode, 2 * slot_id));
      be.bias_m = re.lognormal_mean(nl.box_bias_mean_m, nl.bias_shape);
    }
    if (body_blocked && !de.blocked) {
      Rng re(mix_seed(opt.seed, kStreamEpisode, 2 * slot_id + 1));
      de.bias_m = re.lognormal_mean(nl.body_bias_mean_m, nl.bias_shape);
    }
    be.blocked = box_blocked;
    de.blocked = body_blocked;

    // Random (renewal) NLOS episode covering t_us, if any.
    const EpisodeInterval* episode = nullptr;
    std::vector<EpisodeInterval>& eps = episodes[pair];
    size_t& cur = episode_cursor[pair];
    while (cur < eps.size() && eps[cur].end_us <= t_us) ++cur;
    if (cur < eps.size() && eps[cur].start_us <= t_us) episode = &eps[cur];

    const bool burst_lost = burst_loss > 0.0 && bursts[pair].step(burst_loss, sc.uwb.burst_mean_len);
    if (in_outage(sc, t_us) || blocked(a, t_us) || u_loss < packet_loss || burst_lost) return;
    if (sc.uwb.max_range_m > 0.0 && true_range > sc.uwb.max_range_m) return;  // out of coverage

    const double js = nl.bias_jitter_shape;
    const double jitter_norm = -0.5 * js * js;  // keeps E[jitter] = 1
    double bias = 0.0;
    RangeCause cause = RangeCause::kLos;
    if (noisy && box_blocked) {
      bias += be.bias_m * std::exp(js * n_box_jitter + jitter_norm) + nl.box_extra_sigma_m * n_box_extra;
      cause = RangeCause::kBox;
    }
    if (noisy && body_blocked) {
      bias += de.bias_m * std::exp(js * n_body_jitter + jitter_norm) + nl.body_extra_sigma_m * n_body_extra;
      if (cause == RangeCause::kLos) cause = RangeCause::kBody;
    }
    if (episode != nullptr) {
      Rng r2(mix_seed(opt.seed, kStreamSlot2, slot_id));
      const double n_ep_jitter = r2.normal();
      const double n_ep_extra = r2.normal();
      bias += episode->bias_m * std::exp(js * n_ep_jitter + jitter_norm) + nl.episode_extra_sigma_m * n_ep_extra;
      if (cause == RangeCause::kLos) cause = RangeCause::kEpisode;
    }
    const bool geometric_nlos = cause != RangeCause::kLos;
    if (u_outlier < outlier_prob) {
      double mag = std::exp(ln_out_min + u_out_mag * (ln_out_max - ln_out_min));
      if (u_out_sign >= nl.outlier_positive_prob) mag = -std::min(mag, 0.5 * true_range);
      bias += mag;
      cause = RangeCause::kOutlier;
    }
    const PairError& pe = out.pair_errors[pair];
    const double systematic = pe.offset_m + pe.scale * true_range;
    const double range = quantise(std::max(0.0, true_range + systematic + sigma * n_range + bias), lsb);

    out.rec.uwb.push_back(range_row(t_us, anchor.id, tag.id, range, cause, geometric_nlos, true_range,
                                    sc.uwb.channel_diagnostics, ch, n_shadow, n_gap));
    out.range_truth.push_back(RangeTruth{true_range, bias, systematic, cause});
  });
}

// GNSS fixes of the antenna (truth + R lever) at k / rate_hz: per navigation
// axis a first-order Gauss-Markov error plus white noise; in multipath windows
// an extra horizontal bias of multipath_bias_m whose direction turns slowly
// (vertical: half of it, phase-shifted), fix single, claimed sigma and velocity
// noise x multipath_claim_factor; none in blocked windows. Own random streams:
// one sequential stream draws the same numbers every epoch (fix or not), one
// the latencies, one per window its multipath parameters.
void simulate_gnss(const Scenario& sc, const SimOptions& opt, const Trajectory& traj, uint64_t dur_us,
                   SimOutput& out) {
  const GnssConfig& g = sc.gnss;
  if (!g.enabled) return;
  const uint64_t period_us = static_cast<uint64_t>(std::llround(1e6 / g.rate_hz));
  const double phi = std::exp(-static_cast<double>(period_us) * 1e-6 / g.tau_s);
  const double drive = std::sqrt(1.0 - phi * phi);
  const double gm_sigma[3] = {g.sigma_h_m, g.sigma_h_m, g.sigma_v_m};
  double claim_m[3];
  for (int i = 0; i < 3; ++i) claim_m[i] = std::hypot(gm_sigma[i], g.sigma_white_m) * g.claim_ratio;

  struct Multipath {
    double theta0_rad = 0.0;     // bias direction at the window start, from nav x, CCW
    double turn_radps = 0.0;     // its turn rate
    double phase_v_rad = 0.0;    // vertical component: 0.5 bias sin(theta + phase)
  };
  std::vector<Multipath> mp(g.windows.size());
  for (size_t w = 0; w < g.windows.size(); ++w) {
    Rng r(mix_seed(opt.seed, kStreamGnss, 100 + w));
    mp[w].theta0_rad = r.uniform(-kPi, kPi);
    mp[w].turn_radps = (r.uniform() < 0.5 ? -1.0 : 1.0) * r.uniform(0.5, 1.0) * g.multipath_turn_dps * kDeg;
    mp[w].phase_v_rad = r.uniform(-kPi, kPi);
  }

  Rng err(mix_seed(opt.seed, kStreamGnss, 1));
  Rng lat(mix_seed(opt.seed, kStreamGnss, 2));
  double gm[3];
  for (int i = 0; i < 3; ++i) gm[i] = gm_sigma[i] * err.normal();  // stationary from the start
  // Exactly the lever the recording carries (float, meta.ini gnss_lever_m).
  const Vec3f lever_f = to_vec3f(g.lever_body_m);
  const Eigen::Vector3d lever(static_cast<double>(lever_f.x), static_cast<double>(lever_f.y),
                              static_cast<double>(lever_f.z));
  std::vector<GnssFix> fixes;
  std::vector<GnssTruth> truths;
  for (uint64_t k = 0;; ++k) {
    const uint64_t t_us = k * period_us;
    if (t_us >= dur_us) break;
    if (k > 0) {
      for (int i = 0; i < 3; ++i) gm[i] = phi * gm[i] + gm_sigma[i] * drive * err.normal();
    }
    double n_white[3];
    double n_vel[3];
    for (double& n : n_white) n = err.normal();
    for (double& n : n_vel) n = err.normal();
    const double u_sv = err.uniform();
    const double u_latency = lat.uniform();

    const double t_s = static_cast<double>(t_us) * 1e-6;
    bool blocked = false;
    const GnssWindow* window = nullptr;
    size_t window_index = 0;
    for (size_t w = 0; w < g.windows.size(); ++w) {
      const GnssWindow& gw = g.windows[w];
      if (t_s < gw.start_s || t_s >= gw.end_s) continue;
      if (gw.kind == GnssWindowKind::kBlocked) blocked = true;
      if (gw.kind == GnssWindowKind::kMultipath && window == nullptr) {
        window = &gw;
        window_index = w;
      }
    }
    if (blocked) continue;
    const double latency_ms = std::max(0.0, g.latency_ms + g.latency_jitter_ms * (2.0 * u_latency - 1.0));
    GnssFix fix;
    fix.t_us = t_us;
    fix.rx_t_us = t_us + static_cast<uint64_t>(std::llround(latency_ms * 1e3));
    if (fix.rx_t_us >= dur_us) continue;  // arrives after the end of the recording

    const KinState st = traj.at(t_us);
    const Eigen::Vector3d antenna = st.pos_nav_m + st.R_nav_body * lever;
    // Lever-arm term: w_nav x (R l) = R (w_body x l), with the true body rate.
    const Eigen::Vector3d antenna_vel = st.vel_nav_mps + st.R_nav_body * st.gyro_body_radps.cross(lever);
    Eigen::Vector3d error(gm[0] + g.sigma_white_m * n_white[0], gm[1] + g.sigma_white_m * n_white[1],
                          gm[2] + g.sigma_white_m * n_white[2]);
    double factor = 1.0;
    if (window != nullptr) {
      const Multipath& m = mp[window_index];
      const double theta = m.theta0_rad + m.turn_radps * (t_s - window->start_s);
      error += g.multipath_bias_m *
               Eigen::Vector3d(std::cos(theta), std::sin(theta), 0.5 * std::sin(theta + m.phase_v_rad));
      factor = g.multipath_claim_factor;
    }
    const Eigen::Vector3d pos = antenna + error;
    const Eigen::Vector3d vel =
        antenna_vel + g.vel_sigma_mps * factor * Eigen::Vector3d(n_vel[0], n_vel[1], n_vel[2]);
    fix.pos_nav_m = Vec3f{static_cast<float>(pos.x()), static_cast<float>(pos.y()), static_cast<float>(pos.z())};
    fix.pos_sigma_m = Vec3f{static_cast<float>(claim_m[0] * factor), static_cast<float>(claim_m[1] * factor),
                            static_cast<float>(claim_m[2] * factor)};
    fix.vel_nav_mps = Vec3f{static_cast<float>(vel.x()), static_cast<float>(vel.y()), static_cast<float>(vel.z())};
    fix.vel_sigma_mps = static_cast<float>(g.vel_sigma_mps * g.claim_ratio * factor);
    fix.fix = window != nullptr ? GnssFixType::kSingle : GnssFixType::kDgnss;
    if (g.num_sv > 0) {
      const int base = static_cast<int>(window != nullptr ? (g.num_sv + 1) / 2 : g.num_sv);
      const int jitter = std::min(2, static_cast<int>(u_sv * 3.0)) - 1;  // -1, 0 or +1
      fix.num_sv = static_cast<uint8_t>(std::min(255, std::max(4, base + jitter)));
    }
    GnssTruth truth;
    for (int i = 0; i < 3; ++i) {
      truth.antenna_nav_m[i] = antenna[i];
      truth.antenna_vel_nav_mps[i] = antenna_vel[i];
      truth.error_nav_m[i] = error[i];
    }
    truth.multipath = window != nullptr;
    fixes.push_back(fix);
    truths.push_back(truth);
  }
  // Arrival order (the recording's order); jitter above half the period can swap neighbours.
  std::vector<size_t> order(fixes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return fixes[a].rx_t_us < fixes[b].rx_t_us; });
  out.rec.gnss.reserve(fixes.size());
  out.gnss_truth.reserve(fixes.size());
  for (size_t i : order) {
    out.rec.gnss.push_back(fixes[i]);
    out.gnss_truth.push_back(truths[i]);
  }
}

// Broadcast states of the neighbour vehicles at coop.rate_hz (a random phase
// per vehicle): the tag truth plus, per axis of the vehicle's along-track /
// cross-track / up frame, a stationary first-order Gauss-Markov error whose
// 1-sigmas the broadcast covariance claims (rotated into the navigation frame
// by the vehicle's heading), so the claim is honest; the velocity is the tag's
// true velocity plus white noise; latency mean +- jitter. Own random streams
// per vehicle (errors, latencies).
void simulate_neighbour_states(const Scenario& sc, const SimOptions& opt, const NeighbourTracks& tracks,
                               uint64_t dur_us, SimOutput& out) {
  const CoopConfig& c = sc.coop;
  const uint64_t period_us = static_cast<uint64_t>(std::llround(1e6 / c.rate_hz));
  struct Made {
    NeighbourState state;
    NeighbourTruth truth;
  };
  std::vector<Made> made;
  for (size_t i = 0; i < tracks.size(); ++i) {
    const NeighbourDef& n = tracks.vehicle(i);
    Rng err(mix_seed(opt.seed, kStreamCoop, 1000 + i));
    Rng lat(mix_seed(opt.seed, kStreamCoop, 2000 + i));
    const uint64_t phase_us =
        std::min(period_us - 1, static_cast<uint64_t>(lat.uniform() * static_cast<double>(period_us)));
    const double phi = std::exp(-static_cast<double>(period_us) * 1e-6 / n.tau_s);
    const double drive = std::sqrt(1.0 - phi * phi);
    double e[3];
    for (int k = 0; k < 3; ++k) e[k] = n.sigma_m[k] * err.normal();  // stationary from the start
    const Eigen::Vector3d lever(n.tag_lever_body_m[0], n.tag_lever_body_m[1], n.tag_lever_body_m[2]);
    for (uint64_t k = 0;; ++k) {
      const uint64_t t_us = phase_us + k * period_us;
      if (t_us >= dur_us) break;
      if (k > 0) {
        for (int a = 0; a < 3; ++a) e[a] = phi * e[a] + n.sigma_m[a] * drive * err.normal();
      }
      double n_vel[3];
      for (double& v : n_vel) v = err.normal();
      const double u_latency = lat.uniform();
      const double latency_ms = std::max(0.0, c.latency_ms + c.latency_jitter_ms * (2.0 * u_latency - 1.0));
      Made m;
      m.state.t_us = t_us;
      m.state.rx_t_us = t_us + static_cast<uint64_t>(std::llround(latency_ms * 1e3));
      if (m.state.rx_t_us >= dur_us) continue;  // arrives after the end of the recording

      const KinState st = tracks.at(i, t_us);
      const Eigen::Vector3d tag = st.pos_nav_m + st.R_nav_body * lever;
      const Eigen::Vector3d tag_vel = st.vel_nav_mps + st.R_nav_body * st.gyro_body_radps.cross(lever);
      const double cy = std::cos(st.yaw_rad);
      const double sy = std::sin(st.yaw_rad);
      const Eigen::Vector3d error(cy * e[0] - sy * e[1], sy * e[0] + cy * e[1], e[2]);
      const double va = n.sigma_m[0] * n.sigma_m[0];
      const double vc = n.sigma_m[1] * n.sigma_m[1];
      const double cov[6] = {cy * cy * va + sy * sy * vc, cy * sy * (va - vc) + 0.0, 0.0,  // + 0.0: no -0
                             sy * sy * va + cy * cy * vc, 0.0, n.sigma_m[2] * n.sigma_m[2]};
      const Eigen::Vector3d pos = tag + error;
      const Eigen::Vector3d vel = tag_vel + c.vel_sigma_mps * Eigen::Vector3d(n_vel[0], n_vel[1], n_vel[2]);
      m.state.vehicle_id = n.id;
      m.state.pos_nav_m = Vec3f{static_cast<float>(pos.x()), static_cast<float>(pos.y()), static_cast<float>(pos.z())};
      for (int a = 0; a < 6; ++a) m.state.cov_pos_m2[a] = static_cast<float>(cov[a]);
      m.state.vel_nav_mps =
          Vec3f{static_cast<float>(vel.x()), static_cast<float>(vel.y()), static_cast<float>(vel.z())};
      m.state.cooperative = c.dependent;
      for (int a = 0; a < 3; ++a) {
        m.truth.tag_nav_m[a] = tag[a];
        m.truth.tag_vel_nav_mps[a] = tag_vel[a];
        m.truth.error_nav_m[a] = error[a];
      }
      made.push_back(m);
    }
  }
  // neighbours.csv order (time of validity), then arrival order: what reading the file back gives.
  std::stable_sort(made.begin(), made.end(), [](const Made& a, const Made& b) { return a.state.t_us < b.state.t_us; });
  std::stable_sort(made.begin(), made.end(),
                   [](const Made& a, const Made& b) { return a.state.rx_t_us < b.state.rx_t_us; });
  out.rec.neighbours.reserve(made.size());
  out.neighbour_truth.reserve(made.size());
  for (const Made& m : made) {
    out.rec.neighbours.push_back(m.state);
    out.neighbour_truth.push_back(m.truth);
  }
}

// Ranges from every ego tag to every neighbour's tag, coop.range_rate_hz per
// pair, slots spread evenly over the period (vehicle-major), merged into the
// anchor ranges by time. The anchors' LOS noise, packet loss, outliers,
// coverage, outages, quantisation and channel diagnostics apply; a range whose
// straight line crosses a third vehicle's body box is NLOS: a bias U[min, max]
// drawn when the blockage starts, plus Gaussian extra noise, label 1. Every
// slot draws the same numbers from its own stream, used or not.
void simulate_vehicle_ranges(const Scenario& sc, const SimOptions& opt, const Trajectory& traj,
                             const NeighbourTracks& tracks, uint64_t dur_us, SimOutput& out) {
  const CoopConfig& c = sc.coop;
  const NlosConfig& nl = sc.nlos;
  const ChannelConfig& ch = sc.channel;
  const bool noisy = !opt.ideal_uwb;
  const double packet_loss = noisy ? sc.uwb.packet_loss : 0.0;
  const double sigma = noisy ? sc.uwb.sigma_m : 0.0;
  const double outlier_prob = noisy ? nl.outlier_prob : 0.0;
  const double lsb = noisy ? sc.uwb.range_lsb_m : 0.0;
  const double ln_out_min = std::log(nl.outlier_min_m);
  const double ln_out_max = std::log(nl.outlier_max_m);
  const size_t n_vehicles = tracks.size();
  const size_t n_tags = sc.tags.size();
  const size_t n_pairs = n_vehicles * n_tags;
  const uint64_t period_us = static_cast<uint64_t>(std::llround(1e6 / c.range_rate_hz));
  const uint64_t offset_us = static_cast<uint64_t>(std::llround(c.range_offset_ms * 1e3));
  const uint64_t step_us = period_us / n_pairs;

  std::vector<dataset::UwbRow> rows;
  std::vector<RangeTruth> truths;
  std::vector<Episode> episodes(n_pairs);
  std::vector<KinState> bodies(n_vehicles);
  for (uint64_t k = 0;; ++k) {
    const uint64_t slot_t0 = offset_us + k * period_us;
    if (slot_t0 >= dur_us) break;
    for (size_t pair = 0; pair < n_pairs; ++pair) {
      const uint64_t t_us = slot_t0 + pair * step_us;
      if (t_us >= dur_us) break;
      const size_t i = pair / n_tags;
      const TagDef& tag = sc.tags[pair % n_tags];
      const uint64_t slot_id = k * n_pairs + pair;
      Rng r(mix_seed(opt.seed, kStreamCoopSlot, slot_id));
      const double u_loss = r.uniform();
      const double n_range = r.normal();
      const double u_outlier = r.uniform();
      const double u_out_mag = r.uniform();
      const double u_out_sign = r.uniform();
      const double n_extra = r.normal();
      const double n_shadow = r.normal();
      const double n_gap = r.normal();

      const KinState ego = traj.at(t_us);
      for (size_t m = 0; m < n_vehicles; ++m) bodies[m] = tracks.at(m, t_us);
      const Eigen::Vector3d ego_lever(tag.lever_body_m[0], tag.lever_body_m[1], tag.lever_body_m[2]);
      const Eigen::Vector3d ego_tag = ego.pos_nav_m + ego.R_nav_body * ego_lever;
      const double* l = tracks.vehicle(i).tag_lever_body_m;
      const Eigen::Vector3d other_tag = bodies[i].pos_nav_m + bodies[i].R_nav_body * Eigen::Vector3d(l[0], l[1], l[2]);
      const double true_range = (other_tag - ego_tag).norm();
      bool blocked = false;
      for (size_t m = 0; m < n_vehicles && !blocked; ++m) {
        blocked = m != i && segment_hits_vehicle(ego_tag, other_tag, bodies[m], c.box_m);
      }
      Episode& ep = episodes[pair];
      if (blocked && !ep.blocked) {
        Rng rb(mix_seed(opt.seed, kStreamCoopBias, slot_id));
        ep.bias_m = rb.uniform(c.nlos_bias_min_m, c.nlos_bias_max_m);
      }
      ep.blocked = blocked;

      if (in_outage(sc, t_us) || u_loss < packet_loss) continue;
      if (sc.uwb.max_range_m > 0.0 && true_range > sc.uwb.max_range_m) continue;  // out of coverage

      double bias = 0.0;
      RangeCause cause = RangeCause::kLos;
      if (noisy && blocked) {
        bias += ep.bias_m + c.nlos_extra_sigma_m * n_extra;
        cause = RangeCause::kVehicle;
      }
      const bool geometric_nlos = cause != RangeCause::kLos;
      if (u_outlier < outlier_prob) {
        double mag = std::exp(ln_out_min + u_out_mag * (ln_out_max - ln_out_min));
        if (u_out_sign >= nl.outlier_positive_prob) mag = -std::min(mag, 0.5 * true_range);
        bias += mag;
        cause = RangeCause::kOutlier;
      }
      const double range = quantise(std::max(0.0, true_range + sigma * n_range + bias), lsb);

      rows.push_back(range_row(t_us, tracks.vehicle(i).id, tag.id, range, cause, geometric_nlos, true_range,
                               sc.uwb.channel_diagnostics, ch, n_shadow, n_gap));
      truths.push_back(RangeTruth{true_range, bias, 0.0, cause});
    }
  }

  // Merge by time (anchor ranges first on ties), keeping range_truth parallel.
  std::vector<dataset::UwbRow> merged_rows;
  std::vector<RangeTruth> merged_truths;
  merged_rows.reserve(out.rec.uwb.size() + rows.size());
  merged_truths.reserve(merged_rows.capacity());
  size_t a = 0;
  size_t b = 0;
  while (a < out.rec.uwb.size() || b < rows.size()) {
    if (b >= rows.size() || (a < out.rec.uwb.size() && out.rec.uwb[a].range.t_us <= rows[b].range.t_us)) {
      merged_rows.push_back(out.rec.uwb[a]);
      merged_truths.push_back(out.range_truth[a]);
      ++a;
    } else {
      merged_rows.push_back(rows[b]);
      merged_truths.push_back(truths[b]);
      ++b;
    }
  }
  out.rec.uwb = std::move(merged_rows);
  out.range_truth = std::move(merged_truths);
}

// Seed 000 §2.1: per (tag, anchor), a random `protocol_fraction` of the ranges
// gets an added error of mean U[min, max] plus Gaussian spread, labelled NLOS.
void apply_protocol(const Scenario& sc, const SimOptions& opt, SimOutput& out) {
  const NlosConfig& nl = sc.nlos;
  for (const TagDef& tag : sc.tags) {
    for (const AnchorDef& anchor : sc.anchors) {
      std::vector<size_t> idx;
      for (size_t i = 0; i < out.rec.uwb.size(); ++i) {
        const UwbRange& r = out.rec.uwb[i].range;
        if (r.anchor_id == anchor.id && r.tag_id == tag.id) idx.push_back(i);
      }
      Rng rng(mix_seed(opt.seed, kStreamProtocol, (static_cast<uint64_t>(tag.id) << 16U) | anchor.id));
      for (size_t i = idx.size(); i > 1; --i) {
        const size_t pick = static_cast<size_t>(rng.below(i));
        std::swap(idx[i - 1], idx[pick]);
      }
      const size_t n_nlos =
          static_cast<size_t>(std::floor(nl.protocol_fraction * static_cast<double>(idx.size()) + 0.5));
      for (size_t m = 0; m < n_nlos; ++m) {
        const size_t i = idx[m];
        const double mean = rng.uniform(nl.protocol_mean_min_m, nl.protocol_mean_max_m);
        const double added = mean + nl.protocol_spread_m * rng.normal();
        dataset::UwbRow& row = out.rec.uwb[i];
        row.range.range_m = static_cast<float>(std::max(0.0, static_cast<double>(row.range.range_m) + added));
        row.nlos_label = 1;
        out.range_truth[i].bias_m += added;
        out.range_truth[i].cause = RangeCause::kProtocol;
      }
    }
  }
}

}  // namespace

Status simulate_scenario(const Scenario& scenario, const SimOptions& options, SimOutput& out,
                         std::string* error) {
  const Status v = validate_scenario(scenario, error);
  if (!ok(v)) return v;
  out = SimOutput{};
  out.scenario = scenario;
  out.anchors_surveyed = survey_anchors(scenario, options);
  const Status site = fill_site(scenario, out.anchors_surveyed, out.rec.site, error);
  if (!ok(site)) return site;
  out.pair_errors = draw_pair_errors(scenario, options);
  out.blockages = draw_blockages(scenario, options);
  fill_meta(scenario, options, out.rec);
  fill_meta_errors(scenario, options, out, out.rec);
  fill_meta_coop(scenario, out.rec);

  const uint64_t dur_us = static_cast<uint64_t>(std::llround(scenario.duration_s * 1e6));
  Trajectory traj;
  traj.build(scenario, scenario.duration_s);
  simulate_imu(scenario, options, traj, dur_us, out);
  simulate_uwb(scenario, options, traj, dur_us, out);
  if (scenario.nlos.protocol && !options.ideal_uwb) apply_protocol(scenario, options, out);
  simulate_gnss(scenario, options, traj, dur_us, out);
  if (!scenario.coop.vehicles.empty()) {
    NeighbourTracks tracks;
    tracks.build(scenario, scenario.duration_s);
    simulate_neighbour_states(scenario, options, tracks, dur_us, out);
    simulate_vehicle_ranges(scenario, options, traj, tracks, dur_us, out);
  }
  return Status::kOk;
}

Status simulate(const std::string& scenario, const SimOptions& options, SimOutput& out, std::string* error) {
  Scenario sc;
  const Status st = load_scenario(scenario, sc, error);
  if (!ok(st)) return st;
  return simulate_scenario(sc, options, out, error);
}

Status simulate(const std::string& scenario, uint64_t seed, dataset::Recording& out, std::string* error) {
  SimOptions opt;
  opt.seed = seed;
  SimOutput full;
  const Status st = simulate(scenario, opt, full, error);
  if (!ok(st)) return st;
  out = std::move(full.rec);
  return Status::kOk;
}

}  // namespace uwbnav::sim
