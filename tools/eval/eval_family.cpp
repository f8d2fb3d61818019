// `uwbnav eval family` (see eval_family.hpp): simulates the family drives in
// memory, replays the firmware over each (all cores), pools accuracy,
// availability and honesty figures per cell and prints them.
#include "tools/eval/eval_family.hpp"
#include "tools/eval/text_table.hpp"

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include "firmware/app.hpp"
#include "tools/cli/args.hpp"
#include "tools/dataset/text_source.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/sim/family.hpp"

namespace uwbnav::eval {
namespace {

constexpr double kChi2_2dof_95 = 5.991;  // 95 % quantile of chi^2 with 2 degrees of freedom
constexpr double kChi2_1dof_95 = 3.841;  // 95 % quantile of chi^2 with 1 degree of freedom

bool is_good(const dataset::EstimateRow& e) {
  return (e.status == static_cast<int>(NavStatus::kValid) || e.status == static_cast<int>(NavStatus::kDegraded)) &&
         std::isfinite(e.pos_nav_m[0]) && std::isfinite(e.pos_nav_m[1]);
}

double median(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double worst(const std::vector<double>& v) {
  double w = std::nan("");
  for (double x : v) {
    if (std::isfinite(x) && !(x <= w)) w = x;
  }
  return w;
}

double ratio(double num, double den) { return den > 0.0 ? num / den : std::nan(""); }

bool is_dir(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::vector<std::string> subdirs(const std::string& dir) {
  std::vector<std::string> out;
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return out;
  while (const dirent* e = ::readdir(d)) {
    const std::string n = e->d_name;
    if (n == "." || n == "..") continue;
    if (is_dir(dir + "/" + n)) out.push_back(dir + "/" + n);
  }
  ::closedir(d);
  std::sort(out.begin(), out.end());
  return out;
}

std::string num(double v, int digits) {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}
std::string pct(double v) { return std::isfinite(v) ? num(100.0 * v, 1) + " %" : "n/a"; }


}  // namespace

RecoveryCounts count_reinits(const NavDiagnostics& diag) {
  RecoveryCounts c;
  c.resets = diag.resets;
  c.reinits = diag.reinits;
  c.inflations = diag.inflations;
  c.reanchors = diag.reanchors;
  return c;
}

DriveMetrics drive_metrics(const dataset::Recording& rec, const ReplayResult& res) {
  DriveMetrics m;
  m.ok = true;
  m.name = rec.name();
  m.rmse_h_m = m.max_h_m = m.p95_h_m = m.ttfe_s = std::nan("");
  const std::vector<dataset::EstimateRow>& est = res.estimates;
  m.recoveries = count_reinits(res.diag);
  m.ranges_used = res.ranges_used;
  m.ranges_rejected = res.ranges_rejected;
  if (est.empty()) return m;
  m.hours = static_cast<double>(est.back().t_us - est.front().t_us) / 3.6e9;

  // Availability: from the first good epoch on (or from the first range when there is none).
  const uint64_t first_range_us = rec.uwb.empty() ? est.front().t_us : rec.uwb.front().range.t_us;
  size_t first = est.size();
  for (size_t i = 0; i < est.size(); ++i) {
    if (is_good(est[i])) {
      first = i;
      break;
    }
  }
  if (first == est.size()) {
    for (const auto& e : est) m.epochs += e.t_us >= first_range_us ? 1 : 0;
    m.longest_gap_s = est.back().t_us > first_range_us ? static_cast<double>(est.back().t_us - first_range_us) * 1e-6 : 0.0;
  } else {
    m.ttfe_s = est[first].t_us >= first_range_us ? static_cast<double>(est[first].t_us - first_range_us) * 1e-6 : 0.0;
    uint64_t last_good = est[first].t_us;
    for (size_t i = first; i < est.size(); ++i) {
      ++m.epochs;
      if (!is_good(est[i])) continue;
      ++m.good;
      const uint64_t gap_us = est[i].t_us - last_good;
      if (gap_us > kCyclePeriodUs) m.longest_gap_s = std::max(m.longest_gap_s, static_cast<double>(gap_us - kCyclePeriodUs) * 1e-6);
      last_good = est[i].t_us;
    }
    m.longest_gap_s = std::max(m.longest_gap_s, static_cast<double>(est.back().t_us - last_good) * 1e-6);
  }

  // Sparse anchors: epochs inside a stretch of at least kSparseMinS during which
  // fewer than 3 distinct anchors (vehicle ids excluded) were heard within
  // kHeardWindowUs before each epoch.
  constexpr uint64_t kHeardWindowUs = 2000000;
  constexpr double kSparseMinS = 20.0;
  std::vector<char> sparse(est.size(), 0);
  {
    std::map<uint16_t, uint64_t> heard_us;  // anchor id -> last time heard
    size_t next_row = 0;
    for (size_t i = 0; i < est.size(); ++i) {
      const uint64_t t_us = est[i].t_us;
      while (next_row < rec.uwb.size() && rec.uwb[next_row].range.t_us <= t_us) {
        const UwbRange& r = rec.uwb[next_row++].range;
        if (!is_vehicle_id(r.anchor_id)) heard_us[r.anchor_id] = r.t_us;
      }
      size_t n = 0;
      for (const auto& kv : heard_us) n += kv.second + kHeardWindowUs >= t_us ? 1U : 0U;
      sparse[i] = n < 3 ? 1 : 0;
    }
    for (size_t i = 0; i < est.size();) {
      size_t j = i;
      while (j < est.size() && sparse[j] == sparse[i]) ++j;
      const double span_s = static_cast<double>(est[j - 1].t_us - est[i].t_us) * 1e-6;
      if (sparse[i] != 0 && span_s < kSparseMinS) std::fill(sparse.begin() + static_cast<long>(i), sparse.begin() + static_cast<long>(j), 0);
      i = j;
    }
  }

  // Accuracy and honesty against truth.
  std::vector<double> h_err;
  h_err.reserve(m.good);
  for (size_t i = 0; i < est.size(); ++i) {
    const dataset::EstimateRow& e = est[i];
    if (!is_good(e)) continue;
    double p[3];
    if (!truth_at(rec.truth, e.t_us, p)) continue;
    const double ex = e.pos_nav_m[0] - p[0];
    const double ey = e.pos_nav_m[1] - p[1];
    const double h = std::hypot(ex, ey);
    h_err.push_back(h);
    m.err_sq_sum += h * h;
    if (e.mode != static_cast<int>(NavMode::kInertial)) {
      ++m.fallback_n;
      m.fallback_sq_sum += h * h;
    }
    const double sx = e.pos_sigma_m[0];
    const double sy = e.pos_sigma_m[1];
    if (sparse[i] != 0) {
      ++m.sparse_n;
      m.sparse_sq_sum += h * h;
      m.sparse_max_m = std::max(m.sparse_max_m, h);
      m.sparse_in2s_xy += (std::fabs(ex) <= 2.0 * sx ? 1U : 0U) + (std::fabs(ey) <= 2.0 * sy ? 1U : 0U);
    }
    if (!(std::isfinite(sx) && std::isfinite(sy) && sx > 0.0 && sy > 0.0)) continue;
    ++m.hon_n;
    const bool in_h = h <= 2.0 * std::sqrt(sx * sx + sy * sy);
    m.in2s_h += in_h ? 1 : 0;
    if (e.mode != static_cast<int>(NavMode::kInertial)) {
      ++m.fallback_hon_n;
      m.fallback_in2s_h += in_h ? 1 : 0;
    }
    m.in2s_x += std::fabs(ex) <= 2.0 * sx ? 1 : 0;
    m.in2s_y += std::fabs(ey) <= 2.0 * sy ? 1 : 0;
    // NEES of the horizontal position with P = [sx^2, r sx sy; r sx sy, sy^2]:
    // e^T P^-1 e = (ex^2/sx^2 - 2 r ex ey/(sx sy) + ey^2/sy^2) / (1 - r^2).
    const double rho = e.pos_xy_corr;
    if (std::isfinite(rho) && std::fabs(rho) < 1.0) {
      const double nx = ex / sx;
      const double ny = ey / sy;
      const double nees = (nx * nx - 2.0 * rho * nx * ny + ny * ny) / (1.0 - rho * rho);
      ++m.nees_n;
      m.nees_sum += nees;
      m.nees_in += nees <= kChi2_2dof_95 ? 1 : 0;
    }
  }
  m.err_n = h_err.size();
  if (!h_err.empty()) {
    m.rmse_h_m = std::sqrt(m.err_sq_sum / static_cast<double>(h_err.size()));
    m.max_h_m = *std::max_element(h_err.begin(), h_err.end());
    m.p95_h_m = quantile(h_err, 0.95);
  }

  // NIS of the ranges the filter fused with a predicted range.
  for (const RangeReport& r : res.ranges) {
    if (!r.used || !std::isfinite(r.innovation_m) || !std::isfinite(r.innovation_var_m2) || !(r.innovation_var_m2 > 0.0F)) {
      continue;
    }
    const double nis = static_cast<double>(r.innovation_m) * static_cast<double>(r.innovation_m) /
                       static_cast<double>(r.innovation_var_m2);
    ++m.nis_n;
    m.nis_sum += nis;
    m.nis_in += nis <= kChi2_1dof_95 ? 1 : 0;
  }

  // NLOS decisions against the labels.
  std::map<std::tuple<uint64_t, uint16_t, uint8_t>, int8_t> labels;
  for (const auto& u : rec.uwb) labels[{u.range.t_us, u.range.anchor_id, u.range.tag_id}] = u.nlos_label;
  std::set<std::tuple<uint64_t, uint16_t, uint8_t>> fused;
  for (const RangeReport& r : res.ranges) {
    if (r.used) fused.insert({r.t_us, r.anchor_id, r.tag_id});
    const auto it = labels.find({r.t_us, r.anchor_id, r.tag_id});
    if (it == labels.end() || it->second < 0) continue;
    m.nlos.add(it->second == 1, r.nlos);
  }
  // Line-of-sight ranges of the recording (issue 19's "fused on line-of-sight
  // data"): every labelled-LOS range counts, also one input validation dropped.
  for (const auto& [key, label] : labels) {
    if (label != 0) continue;
    ++m.los_ranges;
    m.los_fused += fused.count(key) != 0 ? 1 : 0;
  }
  return m;
}

CellSummary summarise_cell(const std::string& name, const std::vector<DriveMetrics>& drives) {
  CellSummary c;
  c.name = name;
  std::vector<double> rmse, mx, p95, ttfe;
  size_t epochs = 0, good = 0, hon = 0, in_h = 0, in_x = 0, in_y = 0, nees_n = 0, nees_in = 0, nis_n = 0, nis_in = 0;
  size_t err_n = 0, fb_n = 0, fb_hon = 0, fb_in = 0, sp_n = 0, sp_in = 0;
  double err_sq = 0.0, sp_sq = 0.0;
  double nees_sum = 0, nis_sum = 0, fb_sq = 0;
  uint64_t resets = 0, reinits = 0, inflations = 0, reanchors = 0, used = 0, rejected = 0, los = 0, los_used = 0;
  Confusion conf;
  for (const DriveMetrics& d : drives) {
    ++c.drives;
    if (!d.ok) {
      ++c.failed;
      continue;
    }
    c.hours += d.hours;
    rmse.push_back(d.rmse_h_m);
    mx.push_back(d.max_h_m);
    p95.push_back(d.p95_h_m);
    ttfe.push_back(d.ttfe_s);
    c.gap_max_s = std::max(c.gap_max_s, d.longest_gap_s);
    epochs += d.epochs;
    good += d.good;
    err_n += d.err_n;
    err_sq += d.err_sq_sum;
    hon += d.hon_n;
    in_h += d.in2s_h;
    in_x += d.in2s_x;
    in_y += d.in2s_y;
    nees_n += d.nees_n;
    nees_in += d.nees_in;
    nees_sum += d.nees_sum;
    nis_n += d.nis_n;
    nis_in += d.nis_in;
    nis_sum += d.nis_sum;
    resets += d.recoveries.resets;
    reinits += d.recoveries.reinits;
    inflations += d.recoveries.inflations;
    reanchors += d.recoveries.reanchors;
    fb_n += d.fallback_n;
    fb_sq += d.fallback_sq_sum;
    fb_hon += d.fallback_hon_n;
    fb_in += d.fallback_in2s_h;
    sp_n += d.sparse_n;
    sp_sq += d.sparse_sq_sum;
    sp_in += d.sparse_in2s_xy;
    c.sparse_max = std::max(c.sparse_max, d.sparse_max_m);
    used += d.ranges_used;
    rejected += d.ranges_rejected;
    los += d.los_ranges;
    los_used += d.los_fused;
    conf.add(d.nlos);
  }
  c.rmse_med = median(rmse);
  c.rmse_worst = worst(rmse);
  c.max_med = median(mx);
  c.max_worst = worst(mx);
  c.p95_med = median(p95);
  c.ttfe_med_s = median(ttfe);
  c.ttfe_max_s = worst(ttfe);
  c.availability = ratio(static_cast<double>(good), static_cast<double>(epochs));
  c.in2s_h = ratio(static_cast<double>(in_h), static_cast<double>(hon));
  c.in2s_x = ratio(static_cast<double>(in_x), static_cast<double>(hon));
  c.in2s_y = ratio(static_cast<double>(in_y), static_cast<double>(hon));
  c.nees_mean = ratio(nees_sum, static_cast<double>(nees_n));
  c.nees_in = ratio(static_cast<double>(nees_in), static_cast<double>(nees_n));
  c.nis_mean = ratio(nis_sum, static_cast<double>(nis_n));
  c.nis_in = ratio(static_cast<double>(nis_in), static_cast<double>(nis_n));
  c.resets_per_h = ratio(static_cast<double>(resets), c.hours);
  c.reinits_per_h = ratio(static_cast<double>(reinits), c.hours);
  c.inflations_per_h = ratio(static_cast<double>(inflations), c.hours);
  c.reanchors_per_h = ratio(static_cast<double>(reanchors), c.hours);
  c.fallback_share = ratio(static_cast<double>(fb_n), static_cast<double>(err_n));
  c.fallback_rmse = fb_n > 0 ? std::sqrt(fb_sq / static_cast<double>(fb_n)) : std::nan("");
  c.inertial_rmse =
      err_n > fb_n ? std::sqrt(std::max(err_sq - fb_sq, 0.0) / static_cast<double>(err_n - fb_n)) : std::nan("");
  c.fallback_in2s_h = ratio(static_cast<double>(fb_in), static_cast<double>(fb_hon));
  c.inertial_in2s_h = ratio(static_cast<double>(in_h - fb_in), static_cast<double>(hon - fb_hon));
  c.fused_share = ratio(static_cast<double>(used), static_cast<double>(used + rejected));
  c.sparse_share = ratio(static_cast<double>(sp_n), static_cast<double>(err_n));
  c.sparse_rmse = sp_n > 0 ? std::sqrt(sp_sq / static_cast<double>(sp_n)) : std::nan("");
  c.sparse_in2s = ratio(static_cast<double>(sp_in), 2.0 * static_cast<double>(sp_n));
  if (sp_n == 0) c.sparse_max = std::nan("");
  c.nlos_precision = conf.precision();
  c.nlos_recall = conf.recall();
  c.los_fused_share = ratio(static_cast<double>(los_used), static_cast<double>(los));
  c.nlos_false_alarm = conf.false_alarm_rate();
  return c;
}

bool parse_seed_set(const std::string& text, uint64_t& first, uint64_t& last) {
  if (text == "tuning") {
    first = sim::kTuningSeedFirst;
    last = sim::kTuningSeedLast;
    return true;
  }
  if (text == "reporting") {
    first = sim::kReportingSeedFirst;
    last = sim::kReportingSeedLast;
    return true;
  }
  const size_t dash = text.find('-');
  const std::string a = text.substr(0, dash);
  const std::string b = dash == std::string::npos ? a : text.substr(dash + 1);
  if (a.empty() || b.empty() || a[0] == '-' || b[0] == '-') return false;
  char* end_a = nullptr;
  char* end_b = nullptr;
  const unsigned long long x = std::strtoull(a.c_str(), &end_a, 10);
  const unsigned long long y = std::strtoull(b.c_str(), &end_b, 10);
  if (*end_a != '\0' || *end_b != '\0' || y < x) return false;
  first = x;
  last = y;
  return true;
}

std::string find_real_data_dir() {
  const std::string repo = UWBNAV_SOURCE_DIR;
  for (const std::string& d : {repo + "/data", repo + "/../shared/data"}) {
    if (is_dir(d) && !find_recordings(d).empty()) return d;
  }
  return repo + "/../shared/data";
}

std::vector<std::string> find_recordings(const std::string& root) {
  std::vector<std::string> out;
  const auto is_rec = [](const std::string& d) {
    return dataset::text_file_exists(d + "/uwb.csv") && dataset::text_file_exists(d + "/anchors.csv");
  };
  for (const std::string& a : subdirs(root)) {
    if (is_rec(a)) {
      out.push_back(a);
      continue;
    }
    for (const std::string& b : subdirs(a)) {
      if (is_rec(b)) out.push_back(b);
    }
  }
  return out;
}

void print_family_tables(std::FILE* f, const std::vector<CellSummary>& rows, bool markdown) {
  std::vector<std::vector<std::string>> t1;
  std::vector<std::vector<std::string>> t2;
  for (const CellSummary& c : rows) {
    const std::string drives = std::to_string(c.drives) + (c.failed ? " (" + std::to_string(c.failed) + " failed)" : "");
    t1.push_back({c.name, drives, num(c.hours, 2), num(c.rmse_med, 3), num(c.rmse_worst, 3), num(c.max_med, 2),
                  num(c.max_worst, 2), num(c.p95_med, 3), pct(c.availability), num(c.gap_max_s, 1),
                  num(c.ttfe_med_s, 1), num(c.ttfe_max_s, 1)});
    t2.push_back({c.name, pct(c.in2s_h), pct(c.in2s_x), pct(c.in2s_y), num(c.nees_mean, 2), pct(c.nees_in),
                  num(c.nis_mean, 2), pct(c.nis_in), num(c.resets_per_h, 1), num(c.inflations_per_h, 1),
                  num(c.reanchors_per_h, 1), num(c.reinits_per_h, 1),
                  pct(c.fallback_share), num(c.fallback_rmse, 3), pct(c.fallback_in2s_h), num(c.inertial_rmse, 3),
                  pct(c.inertial_in2s_h), pct(c.fused_share), pct(c.los_fused_share), pct(c.nlos_false_alarm),
                  pct(c.nlos_precision), pct(c.nlos_recall)});
  }
  std::fprintf(f, "%sAccuracy and availability (horizontal error of the body origin; medians and worst over drives)%s\n\n",
               markdown ? "**" : "", markdown ? "**" : "");
  print_table(f,
              {"cell", "drives", "hours", "RMSE med [m]", "RMSE worst [m]", "MAX med [m]", "MAX worst [m]",
               "p95 med [m]", "avail", "gap max [s]", "TTFE med [s]", "TTFE max [s]"},
              t1, markdown);
  std::fprintf(f, "\n%sHonesty and robustness (pooled over the epochs / ranges of all drives)%s\n\n",
               markdown ? "**" : "", markdown ? "**" : "");
  print_table(f,
              {"cell", "in 2sig h", "in 2sig x", "in 2sig y", "NEES mean", "NEES<=5.99", "NIS mean", "NIS<=3.84",
               "resets/h", "inflate/h", "re-anchor/h", "re-align/h", "fallback", "fallback RMSE [m]",
               "fallback in 2sig h", "IMU filter RMSE [m]", "IMU filter in 2sig h", "fused", "LOS fused", "NLOS FA",
               "NLOS P", "NLOS R"},
              t2, markdown);
  // Sparse anchors (cells where the vehicle sometimes hears fewer than 3 anchors).
  std::vector<std::vector<std::string>> t3;
  for (const CellSummary& c : rows) {
    if (!(c.sparse_share > 0.0)) continue;
    t3.push_back({c.name, pct(c.sparse_share), num(c.sparse_rmse, 3), num(c.sparse_max, 2), pct(c.sparse_in2s)});
  }
  if (t3.empty()) return;
  std::fprintf(f, "\n%sWhere fewer than 3 anchors are heard for 20 s or more (< 3 distinct anchors ranged in the 2 s before each epoch; pooled)%s\n\n",
               markdown ? "**" : "", markdown ? "**" : "");
  print_table(f, {"cell", "share of epochs", "RMSE [m]", "MAX worst [m]", "in 2sig x,y"}, t3, markdown);
}

int run_eval_family(int argc, char** argv) {
  const cli::Args args(argc, argv, {"--fast", "--markdown", "--verbose", "--real"});
  const char* usage =
      "usage: uwbnav eval family [--cells a,b] [--seeds tuning|reporting|N-M] [--drives-per-cell K]\n"
      "                          [--param name=value]... [--fast] [--markdown] [--verbose] [--jobs N]\n"
      "       uwbnav eval family --real [--data DIR] [--param name=value]... [--markdown]\n"
      "  tuning seeds 1-99 (develop and tune here), reporting seeds 1000-1999 (report here only)\n";
  const std::string bad = args.unknown({"--cells", "--seeds", "--drives-per-cell", "--param", "--fast", "--markdown",
                                        "--verbose", "--jobs", "--real", "--data"});
  if (!args.error().empty() || !bad.empty() || !args.positional().empty()) {
    std::fprintf(stderr, "%s", usage);
    if (!args.error().empty()) std::fprintf(stderr, "uwbnav eval family: %s\n", args.error().c_str());
    if (!bad.empty() && bad != "--help") std::fprintf(stderr, "uwbnav eval family: unknown option %s\n", bad.c_str());
    return 2;
  }
  const bool fast = args.has("--fast");
  const bool markdown = args.has("--markdown");
  const bool verbose = args.has("--verbose");
  const bool real = args.has("--real");
  ReplayOptions ropt;
  ropt.keep_in_memory = true;
  if (!cli::parse_param_options(args, "uwbnav eval family", &ropt.params)) return 2;
  uint64_t jobs64 = std::max(1U, std::thread::hardware_concurrency());
  if (!args.get_u64("--jobs", jobs64, &jobs64) || jobs64 == 0) {
    std::fprintf(stderr, "uwbnav eval family: --jobs needs a positive integer\n");
    return 2;
  }

  // The work list: family drives (cell, seed) or real recordings.
  struct Task {
    std::string cell;  // family cell, or "" for a real recording
    uint64_t seed = 0;
    std::string dir;   // real recording
  };
  std::vector<Task> tasks;
  std::vector<std::string> cells;
  std::string seeds_text;
  if (real) {
    const std::string root = args.has("--data") ? args.get("--data") : find_real_data_dir();
    for (const std::string& d : find_recordings(root)) tasks.push_back(Task{"", 0, d});
    if (tasks.empty()) {
      std::fprintf(stderr, "uwbnav eval family: no recording (uwb.csv + anchors.csv) under %s\n", root.c_str());
      return 1;
    }
    seeds_text = "real recordings under " + root;
  } else {
    if (args.has("--cells")) {
      std::stringstream ss(args.get("--cells"));
      std::string c;
      while (std::getline(ss, c, ',')) {
        if (!c.empty()) cells.push_back(c);
      }
    } else {
      for (const auto& c : sim::family_cells()) cells.push_back(c.name);
    }
    for (const std::string& c : cells) {
      bool known = false;
      for (const auto& fc : sim::family_cells()) known = known || fc.name == c;
      if (!known) {
        std::fprintf(stderr, "uwbnav eval family: unknown cell '%s' (uwbnav sim --list)\n", c.c_str());
        return 2;
      }
    }
    const std::string set = args.get("--seeds", "tuning");
    uint64_t first = 0;
    uint64_t last = 0;
    if (!parse_seed_set(set, first, last)) {
      std::fprintf(stderr, "uwbnav eval family: --seeds must be tuning, reporting, N-M or N, got '%s'\n", set.c_str());
      return 2;
    }
    const bool named = set == "tuning" || set == "reporting";
    uint64_t per_cell = named ? (fast ? 2 : 20) : last - first + 1;
    if (!args.get_u64("--drives-per-cell", per_cell, &per_cell) || per_cell == 0) {
      std::fprintf(stderr, "uwbnav eval family: --drives-per-cell needs a positive integer\n");
      return 2;
    }
    per_cell = std::min<uint64_t>(per_cell, last - first + 1);
    for (const std::string& c : cells) {
      for (uint64_t s = first; s < first + per_cell; ++s) tasks.push_back(Task{c, s, ""});
    }
    const bool tuning = first >= sim::kTuningSeedFirst && first + per_cell - 1 <= sim::kTuningSeedLast;
    const bool reporting = first >= sim::kReportingSeedFirst && first + per_cell - 1 <= sim::kReportingSeedLast;
    seeds_text = "seeds " + std::to_string(first) + "-" + std::to_string(first + per_cell - 1) + " (" +
                 (tuning ? "TUNING set" : reporting ? "REPORTING set" : "outside the named sets") + "), " +
                 std::to_string(per_cell) + " drives per cell" + (fast ? ", fast subset (short drives)" : "");
  }

  std::vector<DriveMetrics> results(tasks.size());
  std::atomic<size_t> next{0};
  std::atomic<size_t> done{0};
  std::mutex print_mutex;
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  const auto t0 = std::chrono::steady_clock::now();
  sim::FamilyOptions fopt;
  fopt.fast = fast;
  const auto worker = [&]() {
    for (;;) {
      const size_t i = next.fetch_add(1);
      if (i >= tasks.size()) return;
      const Task& t = tasks[i];
      const auto w0 = std::chrono::steady_clock::now();
      DriveMetrics m;
      std::string err;
      dataset::Recording rec;
      bool loaded = false;
      if (t.cell.empty()) {
        dataset::ReadReport rep;
        loaded = ok(dataset::read_recording(t.dir, rec, rep));
        if (!loaded) err = "cannot read " + t.dir + ": " + rep.error;
      } else {
        sim::SimOutput so;
        loaded = ok(sim::simulate_family(t.cell, t.seed, fopt, so, &err));
        rec = std::move(so.rec);
      }
      if (loaded) {
        ReplayResult res;
        if (ok(run_replay(rec, ropt, res, &err))) {
          m = drive_metrics(rec, res);
        }
      }
      m.name = t.cell.empty() ? rec.name() : "family:" + t.cell + ":" + std::to_string(t.seed);
      m.error = err;
      m.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
      results[i] = std::move(m);
      const size_t d = ++done;
      if (tty) {
        std::lock_guard<std::mutex> lock(print_mutex);
        std::fprintf(stderr, "\reval family: %zu/%zu drives", d, tasks.size());
      }
    }
  };
  std::vector<std::thread> pool;
  for (uint64_t j = 0; j < std::min<uint64_t>(jobs64, tasks.size()); ++j) pool.emplace_back(worker);
  for (auto& th : pool) th.join();
  if (tty) std::fprintf(stderr, "\n");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  for (const DriveMetrics& m : results) {
    if (!m.ok) std::fprintf(stderr, "uwbnav eval family: %s failed: %s\n", m.name.c_str(), m.error.c_str());
  }
  // Rows in input order (independent of scheduling).
  std::vector<CellSummary> rows;
  if (real) {
    for (const DriveMetrics& m : results) rows.push_back(summarise_cell(m.name, {m}));
    rows.push_back(summarise_cell("all real", results));
  } else {
    for (const std::string& c : cells) {
      std::vector<DriveMetrics> of_cell;
      for (size_t i = 0; i < tasks.size(); ++i) {
        if (tasks[i].cell == c) of_cell.push_back(results[i]);
      }
      rows.push_back(summarise_cell(c, of_cell));
    }
    if (cells.size() > 1) rows.push_back(summarise_cell("all cells", results));
  }

  std::string params = "defaults";
  for (const auto& kv : ropt.params) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%s%s=%g", params == "defaults" ? "" : ", ", kv.first.c_str(), static_cast<double>(kv.second));
    params = (params == "defaults" ? std::string() : params) + buf;
  }
  std::printf("uwbnav eval family: %s; %zu drives; parameters: %s\n\n", seeds_text.c_str(), tasks.size(),
              params.c_str());
  std::printf("Seed sets: tuning 1-99 (develop and tune only here), reporting 1000-1999 (report only here).\n\n");
  print_family_tables(stdout, rows, markdown);
  if (verbose) {
    std::vector<CellSummary> per_drive;
    for (const DriveMetrics& m : results) per_drive.push_back(summarise_cell(m.name, {m}));
    std::printf("\nPer drive:\n\n");
    print_family_tables(stdout, per_drive, markdown);
  }
  std::printf("\nwall time %.1f s on %llu threads\n", wall, static_cast<unsigned long long>(std::min<uint64_t>(jobs64, tasks.size())));
  size_t failed = 0;
  for (const DriveMetrics& m : results) failed += m.ok ? 0 : 1;
  return failed == 0 ? 0 : 1;
}

}  // namespace uwbnav::eval
