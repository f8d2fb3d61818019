// Simulator core: samples the truth trajectory, applies the MEMS IMU error
// model (seed 000 Table 1) and the UWB ranging/NLOS/channel models, and fills a
// format v1 Recording.
#include "tools/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

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
}

Status fill_site(const Scenario& sc, SiteConfig& site, std::string* error) {
  site = SiteConfig{};
  for (const AnchorDef& a : sc.anchors) {
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
  return Status::kOk;
}

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

// UWB: per tag rate_hz round-robin over the anchors, stamped at the ranging
// instant (offset_ms after the IMU grid), with geometry NLOS, outliers, packet
// loss, outages and DW1000-style channel diagnostics.
void simulate_uwb(const Scenario& sc, const SimOptions& opt, const Trajectory& traj, uint64_t dur_us,
                  SimOutput& out) {
  const size_t n_anchors = sc.anchors.size();
  const size_t n_tags = sc.tags.size();
  const uint64_t period_us = static_cast<uint64_t>(std::llround(1e6 / sc.uwb.rate_hz));
  const uint64_t offset_us = static_cast<uint64_t>(std::llround(sc.uwb.offset_ms * 1e3));
  const uint64_t tag_step_us = period_us / n_tags;
  const NlosConfig& nl = sc.nlos;
  const ChannelConfig& ch = sc.channel;
  const bool noisy = !opt.ideal_uwb;
  const double packet_loss = noisy ? sc.uwb.packet_loss : 0.0;
  const double sigma = noisy ? sc.uwb.sigma_m : 0.0;
  const double outlier_prob = noisy ? nl.outlier_prob : 0.0;
  const double ln_out_min = std::log(nl.outlier_min_m);
  const double ln_out_max = std::log(nl.outlier_max_m);

  std::vector<Episode> box_ep(n_tags * n_anchors);
  std::vector<Episode> body_ep(n_tags * n_anchors);
  out.rec.uwb.reserve(static_cast<size_t>(dur_us / period_us + 1) * n_tags);
  out.range_truth.reserve(out.rec.uwb.capacity());

  for (uint64_t k = 0;; ++k) {
    const uint64_t slot_t0 = offset_us + k * period_us;
    if (slot_t0 >= dur_us) break;
    for (size_t j = 0; j < n_tags; ++j) {
      const uint64_t t_us = slot_t0 + j * tag_step_us;
      if (t_us >= dur_us) break;
      const size_t a = static_cast<size_t>((k + j) % n_anchors);
      const uint64_t slot_id = k * n_tags + j;
      const AnchorDef& anchor = sc.anchors[a];
      const TagDef& tag = sc.tags[j];

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

      const KinState st = traj.at(t_us);
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
      Episode& be = box_ep[j * n_anchors + a];
      Episode& de = body_ep[j * n_anchors + a];
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

      if (in_outage(sc, t_us) || u_loss < packet_loss) continue;

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
      const bool geometric_nlos = cause != RangeCause::kLos;
      if (u_outlier < outlier_prob) {
        double mag = std::exp(ln_out_min + u_out_mag * (ln_out_max - ln_out_min));
        if (u_out_sign >= nl.outlier_positive_prob) mag = -std::min(mag, 0.5 * true_range);
        bias += mag;
        cause = RangeCause::kOutlier;
      }
      const double range = std::max(0.0, true_range + sigma * n_range + bias);

      dataset::UwbRow row;
      row.range.t_us = t_us;
      row.range.anchor_id = anchor.id;
      row.range.tag_id = tag.id;
      row.range.range_m = static_cast<float>(range);
      row.nlos_label = cause == RangeCause::kLos ? 0 : 1;
      if (sc.uwb.channel_diagnostics) {
        // Log-distance path loss; blocked paths lose nlos_extra_loss_db and show a
        // larger total-minus-first-path gap (DW1000 diagnostics, folded normal).
        const bool weak_first_path = geometric_nlos || cause == RangeCause::kOutlier;
        double rx = ch.rx_power_1m_dbm - 10.0 * ch.path_loss_exponent * std::log10(std::max(true_range, 0.3)) +
                    ch.shadowing_sigma_db * n_shadow;
        if (geometric_nlos) rx -= ch.nlos_extra_loss_db;
        const double gap = weak_first_path ? std::fabs(ch.nlos_gap_mean_db + ch.nlos_gap_sigma_db * n_gap)
                                           : std::fabs(ch.los_gap_mean_db + ch.los_gap_sigma_db * n_gap);
        row.range.rx_power_dbm = static_cast<float>(rx);
        row.range.fp_power_dbm = static_cast<float>(rx - gap);
      }
      out.rec.uwb.push_back(row);
      out.range_truth.push_back(RangeTruth{true_range, bias, cause});
    }
  }
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
  const Status site = fill_site(scenario, out.rec.site, error);
  if (!ok(site)) return site;
  fill_meta(scenario, options, out.rec);

  const uint64_t dur_us = static_cast<uint64_t>(std::llround(scenario.duration_s * 1e6));
  Trajectory traj;
  traj.build(scenario, scenario.duration_s);
  simulate_imu(scenario, options, traj, dur_us, out);
  simulate_uwb(scenario, options, traj, dur_us, out);
  if (scenario.nlos.protocol && !options.ideal_uwb) apply_protocol(scenario, options, out);
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
