// `uwbnav eval rtk`: BDS-only versus BDS+UWB carrier-phase relative positioning
// on seeded simulated runs (fix rate, wrong fixes, time to first fix, RMSE).
#include "tools/eval/eval_rtk.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "tools/cli/args.hpp"
#include "tools/eval/eval_family.hpp"
#include "tools/sim/family.hpp"

namespace uwbnav::eval {

sim::GnssRawConfig rtk_eval_sim_config(uint64_t seed, bool open_sky) {
  sim::GnssRawConfig c;
  c.seed = seed;
  c.duration_s = 120.0;
  c.dt_s = 1.0;
  // The family: its own stream, so the sky and noise draws of the simulator
  // itself stay those of the seed.
  std::mt19937_64 rng(seed * 0xD1B54A32D192ED03ULL + 0x27ULL);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto draw = [&](double lo, double hi) { return lo + (hi - lo) * u01(rng); };
  c.sigma_code_m = draw(0.3, 0.8);
  c.sigma_phase_m = draw(0.002, 0.004);
  c.sigma_uwb_m = draw(0.05, 0.15);
  c.relative_walk_m_sqrt_s = draw(0.01, 0.05);
  c.canyon_start_s = draw(30.0, 60.0);
  c.canyon_end_s = c.canyon_start_s + draw(20.0, 40.0);
  c.canyon_height_to_halfwidth = draw(0.5, 1.5);
  c.multipath_code_m = draw(0.5, 1.5);
  c.multipath_phase_m = draw(0.005, 0.015);
  if (open_sky) c.canyon_end_s = c.canyon_start_s;
  return c;
}

RtkEvalSettings rtk_eval_settings() { return RtkEvalSettings{}; }

RtkRunMetrics run_rtk_once(const std::vector<sim::GnssRawEpoch>& run, bool use_uwb, const RtkEvalSettings& s) {
  RtkRunMetrics m;
  static thread_local RtkBaseline filter;  // ~78 KiB: not on the stack
  if (!ok(filter.configure(s.params)) || run.empty()) return m;
  double t_prev = run.front().t_s;
  double canyon_end_s = -1.0;
  bool was_in_canyon = false;
  bool fixed_last = false;  // the previous epoch was fixed
  for (const sim::GnssRawEpoch& ep : run) {
    ignore_status(filter.predict(ep.t_s - t_prev, s.relative_motion_psd_m2_s));
    t_prev = ep.t_s;
    if (ep.in_canyon) {
      m.has_canyon = true;
      was_in_canyon = true;
      ++m.canyon_epochs;
    } else {
      if (was_in_canyon && canyon_end_s < 0.0) {
        canyon_end_s = ep.t_s;
        m.fixed_at_exit = fixed_last;
      }
      ++m.open_epochs;
    }
    fixed_last = false;
    const RtkEpoch obs = sim::to_rtk_epoch(ep, use_uwb);
    RtkSolution sol;
    if (!ok(filter.update(obs, sol)) || !sol.valid) continue;
    ++m.epochs;
    m.sq_err_float_m2 += (sol.b_float_nav_m - ep.baseline_nav_m).squaredNorm();
    if (!sol.fixed) continue;
    fixed_last = true;
    ++m.fixed_epochs;
    ++(ep.in_canyon ? m.canyon_fixed : m.open_fixed);
    if (m.ttff_s < 0.0) m.ttff_s = ep.t_s - run.front().t_s;
    if (canyon_end_s >= 0.0 && !m.fixed_at_exit && m.refix_s < 0.0) m.refix_s = ep.t_s - canyon_end_s;
    const double e2 = (sol.b_fixed_nav_m - ep.baseline_nav_m).squaredNorm();
    m.sq_err_fixed_m2 += e2;
    bool wrong = false;
    for (int k = 0; k < sol.n_amb && !wrong; ++k) {
      int64_t truth = 0;
      wrong = !sim::truth_dd_ambiguity(ep, sol.amb_sat_id[k], sol.ref_sat_id, truth) ||
              static_cast<double>(truth) != sol.amb_fixed_cyc(k);
    }
    if (wrong) {
      ++m.wrong_fixed_epochs;
      ++(ep.in_canyon ? m.canyon_wrong : m.open_wrong);
    } else {
      m.sq_err_correct_m2 += e2;
    }
  }
  return m;
}

namespace {

double ratio_or_nan(long num, long den) {
  return den > 0 ? static_cast<double>(num) / static_cast<double>(den) : std::nan("");
}

// Median with +inf for the runs that never reached the event.
double median_inf(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

RtkSummary summarise_rtk(const std::string& name, const std::vector<RtkRunMetrics>& runs) {
  RtkSummary r;
  r.name = name;
  r.runs = static_cast<int>(runs.size());
  long epochs = 0, fixed = 0, wrong = 0;
  long open = 0, open_fixed = 0, open_wrong = 0, canyon = 0, canyon_fixed = 0, canyon_wrong = 0;
  double sq_fix = 0.0, sq_float = 0.0, sq_correct = 0.0;
  std::vector<double> ttff, refix;
  const double inf = std::numeric_limits<double>::infinity();
  r.ttff_max_s = std::nan("");
  for (const RtkRunMetrics& m : runs) {
    epochs += m.epochs;
    fixed += m.fixed_epochs;
    wrong += m.wrong_fixed_epochs;
    open += m.open_epochs;
    open_fixed += m.open_fixed;
    open_wrong += m.open_wrong;
    canyon += m.canyon_epochs;
    canyon_fixed += m.canyon_fixed;
    canyon_wrong += m.canyon_wrong;
    sq_fix += m.sq_err_fixed_m2;
    sq_correct += m.sq_err_correct_m2;
    sq_float += m.sq_err_float_m2;
    if (m.ttff_s < 0.0) {
      ++r.never_fixed;
      ttff.push_back(inf);
    } else {
      ttff.push_back(m.ttff_s);
      r.ttff_max_s = std::isnan(r.ttff_max_s) ? m.ttff_s : std::max(r.ttff_max_s, m.ttff_s);
    }
    if (m.has_canyon && m.fixed_at_exit) ++r.held_at_exit;
    if (m.has_canyon && !m.fixed_at_exit) {
      ++r.lost_at_exit;
      refix.push_back(m.refix_s < 0.0 ? inf : m.refix_s);
      if (m.refix_s < 0.0) ++r.never_refixed;
    }
  }
  r.fix_rate = ratio_or_nan(fixed, epochs);
  r.wrong_fix_rate = ratio_or_nan(wrong, fixed);
  r.open_fix_rate = ratio_or_nan(open_fixed, open);
  r.open_wrong_rate = ratio_or_nan(open_wrong, open_fixed);
  r.canyon_fix_rate = ratio_or_nan(canyon_fixed, canyon);
  r.canyon_wrong_rate = ratio_or_nan(canyon_wrong, canyon_fixed);
  r.fixed_rmse_m = fixed > 0 ? std::sqrt(sq_fix / static_cast<double>(fixed)) : std::nan("");
  r.correct_rmse_m = fixed > wrong ? std::sqrt(sq_correct / static_cast<double>(fixed - wrong)) : std::nan("");
  r.float_rmse_m = epochs > 0 ? std::sqrt(sq_float / static_cast<double>(epochs)) : std::nan("");
  r.ttff_median_s = median_inf(ttff);
  r.refix_median_s = median_inf(refix);
  return r;
}

void print_rtk_table(std::FILE* f, const std::vector<RtkSummary>& rows, bool markdown) {
  if (markdown) {
    std::fprintf(f,
                 "| method | runs | fix rate, open sky | wrong fixes, open sky | fix rate, canyon | wrong fixes, canyon "
                 "| TTFF median [s] | TTFF max [s] | never fixed | fix held at canyon exit | re-fix after canyon, median [s] "
                 "| never re-fixed "
                 "| correct-fix RMSE [m] | float RMSE [m] |\n");
    std::fprintf(f, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    // A figure that does not exist (no canyon, nothing fixed) prints as "–".
    auto cell = [](double v, int decimals, const char* unit) {
      char buf[32];
      if (std::isnan(v)) return std::string("–");
      std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
      return std::string(buf) + unit;
    };
    for (const RtkSummary& r : rows) {
      char held[32] = "–";
      if (r.held_at_exit + r.lost_at_exit > 0) std::snprintf(held, sizeof held, "%d of %d", r.held_at_exit, r.held_at_exit + r.lost_at_exit);
      std::fprintf(f, "| %s | %d | %s | %s | %s | %s | %s | %s | %d | %s | %s | %s | %s | %s |\n", r.name.c_str(), r.runs,
                   cell(100.0 * r.open_fix_rate, 1, " %").c_str(),
                   cell(100.0 * r.open_wrong_rate, 2, " %").c_str(),
                   cell(100.0 * r.canyon_fix_rate, 1, " %").c_str(),
                   cell(100.0 * r.canyon_wrong_rate, 2, " %").c_str(), cell(r.ttff_median_s, 1, "").c_str(),
                   cell(r.ttff_max_s, 1, "").c_str(), r.never_fixed, held, cell(r.refix_median_s, 1, "").c_str(),
                   std::isnan(r.refix_median_s) ? "–" : std::to_string(r.never_refixed).c_str(),
                   cell(r.correct_rmse_m, 4, "").c_str(), cell(r.float_rmse_m, 3, "").c_str());
    }
    return;
  }
  std::fprintf(f, "%-8s %5s %9s %8s %9s %8s %8s %8s %6s %6s %8s %6s %10s %9s\n", "method", "runs", "fix open", "wrong",
               "fix cany", "wrong", "TTFF med", "TTFF max", "never", "held", "refix md", "never", "corr RMSE", "float");
  for (const RtkSummary& r : rows) {
    std::fprintf(f, "%-8s %5d %8.1f%% %7.2f%% %8.1f%% %7.2f%% %8.1f %8.1f %6d %6d %8.1f %6d %10.4f %9.3f\n",
                 r.name.c_str(), r.runs, 100.0 * r.open_fix_rate, 100.0 * r.open_wrong_rate,
                 100.0 * r.canyon_fix_rate, 100.0 * r.canyon_wrong_rate, r.ttff_median_s, r.ttff_max_s,
                 r.never_fixed, r.held_at_exit, r.refix_median_s, r.never_refixed, r.correct_rmse_m, r.float_rmse_m);
  }
}

int run_eval_rtk(int argc, char** argv) {
  const cli::Args args(argc, argv, {"--markdown", "--open-sky"});
  const char* usage =
      "usage: uwbnav eval rtk [--seeds tuning|reporting|N-M] [--runs N] [--slip-rate HZ] [--open-sky] [--markdown]\n"
      "  per seed one randomised 120 s run with a street canyon (tools/sim/gnss_raw), filtered with\n"
      "  BDS only and BDS + UWB; --open-sky drops the canyon.\n"
      "  tuning seeds 1-99 (develop and tune here), reporting seeds 1000-1999 (report here only)\n";
  const std::string bad = args.unknown({"--seeds", "--runs", "--slip-rate", "--open-sky", "--markdown"});
  if (!args.error().empty() || !bad.empty() || !args.positional().empty()) {
    std::fprintf(stderr, "%s", usage);
    if (!args.error().empty()) std::fprintf(stderr, "uwbnav eval rtk: %s\n", args.error().c_str());
    if (!bad.empty() && bad != "--help") std::fprintf(stderr, "uwbnav eval rtk: unknown option %s\n", bad.c_str());
    return 2;
  }
  const std::string set = args.get("--seeds", "tuning");
  uint64_t first = 0, last = 0;
  if (!parse_seed_set(set, first, last)) {
    std::fprintf(stderr, "uwbnav eval rtk: --seeds must be tuning, reporting, N-M or N, got '%s'\n", set.c_str());
    return 2;
  }
  uint64_t runs = last - first + 1;
  if (!args.get_u64("--runs", runs, &runs) || runs == 0) {
    std::fprintf(stderr, "uwbnav eval rtk: --runs needs a positive integer\n");
    return 2;
  }
  runs = std::min<uint64_t>(runs, last - first + 1);
  double slip_rate = 0.0;
  if (args.has("--slip-rate")) {
    char* end = nullptr;
    const std::string v = args.get("--slip-rate");
    slip_rate = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(slip_rate) || slip_rate < 0.0) {
      std::fprintf(stderr, "uwbnav eval rtk: --slip-rate needs a non-negative number [1/s]\n");
      return 2;
    }
  }
  const bool open_sky = args.has("--open-sky");
  const RtkEvalSettings settings = rtk_eval_settings();
  std::vector<RtkRunMetrics> bds, uwb;
  for (uint64_t seed = first; seed < first + runs; ++seed) {
    sim::GnssRawConfig c = rtk_eval_sim_config(seed, open_sky);
    c.slip_rate_hz = slip_rate;
    const std::vector<sim::GnssRawEpoch> run = sim::simulate_gnss_raw(c);
    bds.push_back(run_rtk_once(run, false, settings));
    uwb.push_back(run_rtk_once(run, true, settings));
  }
  const bool tuning = first >= sim::kTuningSeedFirst && first + runs - 1 <= sim::kTuningSeedLast;
  const bool reporting = first >= sim::kReportingSeedFirst && first + runs - 1 <= sim::kReportingSeedLast;
  std::printf("Carrier-phase relative positioning (rtk_baseline), seeds %llu-%llu (%s), %s, slip rate %.4g /s\n",
              static_cast<unsigned long long>(first), static_cast<unsigned long long>(first + runs - 1),
              tuning ? "TUNING set" : reporting ? "REPORTING set" : "outside the named sets",
              open_sky ? "open sky" : "street canyon 20-40 s", slip_rate);
  print_rtk_table(stdout, {summarise_rtk("BDS", bds), summarise_rtk("BDS+UWB", uwb)}, args.has("--markdown"));
  return 0;
}

}  // namespace uwbnav::eval
