// `uwbnav eval outage` (see eval_outage.hpp): simulates the outage drives (the
// family's outage cell and the seed-like parking_outages preset), replays the
// firmware over each twice (ekf.rbf_bridge 0 and 1) and pools the error of the
// epochs inside each outage by drive kind and outage length.
#include "tools/eval/eval_outage.hpp"
#include "tools/eval/text_table.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <thread>
#include <utility>

#include "estimator/navigator.hpp"
#include "tools/cli/args.hpp"
#include "tools/eval/eval_family.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/eval/replay.hpp"
#include "tools/sim/family.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::eval {
namespace {

bool is_good(const dataset::EstimateRow& e) {
  return (e.status == static_cast<int>(NavStatus::kValid) || e.status == static_cast<int>(NavStatus::kDegraded)) &&
         std::isfinite(e.pos_nav_m[0]) && std::isfinite(e.pos_nav_m[1]);
}

std::string num(double v, int digits) {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}
std::string pair(double a, double b, int digits) { return num(a, digits) + "/" + num(b, digits); }
std::string pct(double v) { return std::isfinite(v) ? num(100.0 * v, 1) + " %" : "n/a"; }
double ratio(double a, double b) { return b > 0.0 ? a / b : std::nan(""); }

// Drive kind from the simulated description ("outage seed 3: lot 60x40 m, ...").
std::string drive_kind(const dataset::Recording& rec, bool preset) {
  if (preset) return "parking (preset)";
  const auto it = rec.meta.find("description");
  const std::string d = it == rec.meta.end() ? std::string() : it->second;
  if (d.find(": multicopter") != std::string::npos) return "multicopter";
  if (d.find(": road") != std::string::npos) return "road";
  return "lot";
}

struct GroupKey {
  std::string kind;
  int length_s = 0;
  bool operator<(const GroupKey& o) const { return kind != o.kind ? kind < o.kind : length_s < o.length_s; }
};

struct DriveResult {
  bool ok = false;
  std::string name, error;
  std::map<GroupKey, std::pair<OutageErrors, OutageErrors>> groups;  // without, with
  uint32_t fused = 0;          // pseudo-measurement axes fused (with)
  uint32_t predictions = 0;    // valid network predictions during outages (with)
  uint32_t train_samples = 0;  // training samples (with)
};


}  // namespace

void OutageErrors::add(const OutageErrors& o) {
  outages += o.outages;
  n += o.n;
  sq_x += o.sq_x;
  sq_y += o.sq_y;
  max_x = std::max(max_x, o.max_x);
  max_y = std::max(max_y, o.max_y);
  max_h = std::max(max_h, o.max_h);
  var_x += o.var_x;
  var_y += o.var_y;
  in2s_x += o.in2s_x;
  in2s_y += o.in2s_y;
  in2s_h += o.in2s_h;
}

bool parse_outage_list(const std::string& text, std::vector<OutageSpan>& out) {
  out.clear();
  size_t i = 0;
  while (i < text.size()) {
    if (text[i] == ' ') {
      ++i;
      continue;
    }
    if (text[i] != '[') return false;
    const size_t comma = text.find(',', i);
    const size_t close = text.find(')', i);
    if (comma == std::string::npos || close == std::string::npos || comma > close) return false;
    char* end = nullptr;
    const std::string a = text.substr(i + 1, comma - i - 1);
    const std::string b = text.substr(comma + 1, close - comma - 1);
    OutageSpan s;
    s.start_s = std::strtod(a.c_str(), &end);
    if (end == a.c_str() || *end != '\0') return false;
    s.end_s = std::strtod(b.c_str(), &end);
    if (end == b.c_str() || *end != '\0' || !(s.end_s > s.start_s)) return false;
    out.push_back(s);
    i = close + 1;
  }
  return true;
}

void outage_errors(const std::vector<dataset::EstimateRow>& est, const std::vector<dataset::TruthRow>& truth,
                   const OutageSpan& span, OutageErrors& acc) {
  ++acc.outages;
  const auto t0 = static_cast<uint64_t>(std::llround(span.start_s * 1e6));
  const auto t1 = static_cast<uint64_t>(std::llround(span.end_s * 1e6));
  for (const dataset::EstimateRow& e : est) {
    if (e.t_us < t0 || e.t_us >= t1 || !is_good(e)) continue;
    double p[3];
    if (!truth_at(truth, e.t_us, p)) continue;
    const double ex = e.pos_nav_m[0] - p[0];
    const double ey = e.pos_nav_m[1] - p[1];
    ++acc.n;
    acc.sq_x += ex * ex;
    acc.sq_y += ey * ey;
    acc.max_x = std::max(acc.max_x, std::fabs(ex));
    acc.max_y = std::max(acc.max_y, std::fabs(ey));
    acc.max_h = std::max(acc.max_h, std::hypot(ex, ey));
    const double sx = e.pos_sigma_m[0];
    const double sy = e.pos_sigma_m[1];
    const bool finite = std::isfinite(sx) && std::isfinite(sy);
    acc.var_x += finite ? sx * sx : 0.0;
    acc.var_y += finite ? sy * sy : 0.0;
    acc.in2s_x += finite && std::fabs(ex) <= 2.0 * sx ? 1 : 0;
    acc.in2s_y += finite && std::fabs(ey) <= 2.0 * sy ? 1 : 0;
    acc.in2s_h += finite && std::hypot(ex, ey) <= 2.0 * std::sqrt(sx * sx + sy * sy) ? 1 : 0;
  }
}

int run_eval_outage(int argc, char** argv) {
  const cli::Args args(argc, argv, {"--markdown", "--verbose"});
  const char* usage =
      "usage: uwbnav eval outage [--seeds tuning|reporting|N-M] [--drives K] [--param name=value]...\n"
      "                          [--markdown] [--verbose] [--jobs N]\n"
      "  per seed: family:outage:SEED and sim:parking_outages:SEED, each replayed with ekf.rbf_bridge=0 and =1\n"
      "  tuning seeds 1-99 (develop and tune here), reporting seeds 1000-1999 (report here only)\n";
  const std::string bad = args.unknown({"--seeds", "--drives", "--param", "--markdown", "--verbose", "--jobs"});
  if (!args.error().empty() || !bad.empty() || !args.positional().empty()) {
    std::fprintf(stderr, "%s", usage);
    if (!args.error().empty()) std::fprintf(stderr, "uwbnav eval outage: %s\n", args.error().c_str());
    if (!bad.empty()) std::fprintf(stderr, "uwbnav eval outage: unknown option %s\n", bad.c_str());
    return 2;
  }
  const bool markdown = args.has("--markdown");
  std::vector<std::pair<std::string, float>> user_params;
  if (!cli::parse_param_options(args, "uwbnav eval outage", &user_params)) return 2;
  for (const auto& kv : user_params) {
    if (kv.first == "ekf.rbf_bridge") {
      std::fprintf(stderr, "uwbnav eval outage: ekf.rbf_bridge is set by the evaluation itself (0 and 1)\n");
      return 2;
    }
  }
  uint64_t jobs = std::max(1U, std::thread::hardware_concurrency());
  if (!args.get_u64("--jobs", jobs, &jobs) || jobs == 0) {
    std::fprintf(stderr, "uwbnav eval outage: --jobs needs a positive integer\n");
    return 2;
  }
  const std::string set = args.get("--seeds", "tuning");
  uint64_t first = 0;
  uint64_t last = 0;
  if (!parse_seed_set(set, first, last)) {
    std::fprintf(stderr, "uwbnav eval outage: --seeds must be tuning, reporting, N-M or N, got '%s'\n", set.c_str());
    return 2;
  }
  uint64_t drives = set == "tuning" || set == "reporting" ? 20 : last - first + 1;
  if (!args.get_u64("--drives", drives, &drives) || drives == 0) {
    std::fprintf(stderr, "uwbnav eval outage: --drives needs a positive integer\n");
    return 2;
  }
  drives = std::min<uint64_t>(drives, last - first + 1);

  struct Task {
    bool preset = false;
    uint64_t seed = 0;
  };
  std::vector<Task> tasks;
  for (uint64_t s = first; s < first + drives; ++s) {
    tasks.push_back(Task{false, s});
    tasks.push_back(Task{true, s});
  }
  std::vector<DriveResult> results(tasks.size());
  std::atomic<size_t> next{0};
  std::atomic<size_t> done{0};
  std::mutex print_mutex;
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  const auto worker = [&]() {
    for (;;) {
      const size_t i = next.fetch_add(1);
      if (i >= tasks.size()) return;
      const Task& t = tasks[i];
      DriveResult& r = results[i];
      r.name = t.preset ? "sim:parking_outages:" + std::to_string(t.seed) : "family:outage:" + std::to_string(t.seed);
      dataset::Recording rec;
      bool loaded = false;
      if (t.preset) {
        loaded = ok(sim::simulate("parking_outages", t.seed, rec, &r.error));
      } else {
        sim::SimOutput so;
        loaded = ok(sim::simulate_family("outage", t.seed, sim::FamilyOptions{}, so, &r.error));
        rec = std::move(so.rec);
      }
      std::vector<OutageSpan> spans;
      const auto it = rec.meta.find("sim_outages_s");
      if (loaded && (it == rec.meta.end() || !parse_outage_list(it->second, spans))) {
        loaded = false;
        r.error = "no readable sim_outages_s in meta";
      }
      if (loaded) {
        const std::string kind = drive_kind(rec, t.preset);
        r.ok = true;
        for (int with = 0; with < 2 && r.ok; ++with) {
          ReplayOptions ropt;
          ropt.keep_in_memory = true;
          ropt.params = user_params;
          ropt.params.emplace_back("ekf.rbf_bridge", static_cast<float>(with));
          ReplayResult res;
          if (!ok(run_replay(rec, ropt, res, &r.error))) {
            r.ok = false;
            break;
          }
          for (const OutageSpan& s : spans) {
            auto& g = r.groups[GroupKey{kind, static_cast<int>(std::lround(s.end_s - s.start_s))}];
            outage_errors(res.estimates, rec.truth, s, with != 0 ? g.second : g.first);
          }
          if (with != 0) {
            r.fused = res.diag.rbf.fused;
            r.predictions = res.diag.rbf.predictions;
            r.train_samples = res.diag.rbf.train_samples;
          }
        }
      }
      const size_t d = ++done;
      if (tty) {
        std::lock_guard<std::mutex> lock(print_mutex);
        std::fprintf(stderr, "\reval outage: %zu/%zu drives", d, tasks.size());
      }
    }
  };
  std::vector<std::thread> pool;
  for (uint64_t j = 0; j < std::min<uint64_t>(jobs, tasks.size()); ++j) pool.emplace_back(worker);
  for (auto& th : pool) th.join();
  if (tty) std::fprintf(stderr, "\n");

  std::map<GroupKey, std::pair<OutageErrors, OutageErrors>> groups;
  uint64_t fused = 0, predictions = 0, samples = 0;
  size_t failed = 0;
  for (const DriveResult& r : results) {
    if (!r.ok) {
      ++failed;
      std::fprintf(stderr, "uwbnav eval outage: %s failed: %s\n", r.name.c_str(), r.error.c_str());
      continue;
    }
    for (const auto& kv : r.groups) {
      groups[kv.first].first.add(kv.second.first);
      groups[kv.first].second.add(kv.second.second);
      auto& all = groups[GroupKey{"~all ground", kv.first.length_s}];
      if (kv.first.kind != "multicopter") {
        all.first.add(kv.second.first);
        all.second.add(kv.second.second);
      }
    }
    if (args.has("--verbose")) {
      for (const auto& kv : r.groups) {
        const OutageErrors& a = kv.second.first;
        const OutageErrors& b = kv.second.second;
        const double n = static_cast<double>(std::max<size_t>(a.n, 1));
        std::printf("%s %s %d s: RMSE x/y without %.2f/%.2f, with %.2f/%.2f, MAX h %.2f -> %.2f, in 2sig %.0f -> %.0f %%\n",
                    r.name.c_str(), kv.first.kind.c_str(), kv.first.length_s, std::sqrt(a.sq_x / n), std::sqrt(a.sq_y / n),
                    std::sqrt(b.sq_x / n), std::sqrt(b.sq_y / n), a.max_h, b.max_h, 100.0 * static_cast<double>(a.in2s_h) / n,
                    100.0 * static_cast<double>(b.in2s_h) / n);
      }
    }
    fused += r.fused;
    predictions += r.predictions;
    samples += r.train_samples;
  }

  std::vector<std::vector<std::string>> rows;
  for (const auto& kv : groups) {
    const OutageErrors& a = kv.second.first;
    const OutageErrors& b = kv.second.second;
    const double rx_a = std::sqrt(ratio(a.sq_x, static_cast<double>(a.n)));
    const double ry_a = std::sqrt(ratio(a.sq_y, static_cast<double>(a.n)));
    const double rx_b = std::sqrt(ratio(b.sq_x, static_cast<double>(b.n)));
    const double ry_b = std::sqrt(ratio(b.sq_y, static_cast<double>(b.n)));
    const std::string kind = kv.first.kind == "~all ground" ? "all ground" : kv.first.kind;
    rows.push_back({kind, std::to_string(kv.first.length_s), std::to_string(a.outages), pair(rx_a, ry_a, 2),
                    pair(a.max_x, a.max_y, 2), num(a.max_h, 2),
                    pair(std::sqrt(ratio(a.var_x, static_cast<double>(a.n))), std::sqrt(ratio(a.var_y, static_cast<double>(a.n))), 2),
                    pct(ratio(static_cast<double>(a.in2s_h), static_cast<double>(a.n))), pair(rx_b, ry_b, 2),
                    pair(b.max_x, b.max_y, 2), num(b.max_h, 2),
                    pair(std::sqrt(ratio(b.var_x, static_cast<double>(b.n))), std::sqrt(ratio(b.var_y, static_cast<double>(b.n))), 2),
                    pct(ratio(static_cast<double>(b.in2s_h), static_cast<double>(b.n))),
                    pair(100.0 * (1.0 - rx_b / rx_a), 100.0 * (1.0 - ry_b / ry_a), 0)});
  }
  std::string params = "defaults";
  for (const auto& kv : user_params) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%s%s=%g", params == "defaults" ? "" : ", ", kv.first.c_str(), static_cast<double>(kv.second));
    params = (params == "defaults" ? std::string() : params) + buf;
  }
  const bool tuning = first >= sim::kTuningSeedFirst && first + drives - 1 <= sim::kTuningSeedLast;
  const bool reporting = first >= sim::kReportingSeedFirst && first + drives - 1 <= sim::kReportingSeedLast;
  std::printf("uwbnav eval outage: seeds %llu-%llu (%s), family:outage and sim:parking_outages per seed; parameters: %s\n\n",
              static_cast<unsigned long long>(first), static_cast<unsigned long long>(first + drives - 1),
              tuning ? "TUNING set" : reporting ? "REPORTING set" : "outside the named sets", params.c_str());
  std::printf("%sError during each UWB outage (epochs inside the outage; x/y RMSE and MAX; claimed sigma = RMS of the published 1-sigma; "
              "in 2sig: horizontal error <= 2 sqrt(sx^2 + sy^2)); without = ekf.rbf_bridge 0 (coasting), with = 1; "
              "IP = 1 - RMSE with / RMSE without (seed 004 eq. 14 on RMSE)%s\n\n",
              markdown ? "**" : "", markdown ? "**" : "");
  print_table(stdout,
              {"drive", "outage [s]", "outages", "RMSE x/y without [m]", "MAX x/y without [m]", "MAX h without [m]",
               "sigma x/y without [m]", "in 2sig without", "RMSE x/y with [m]", "MAX x/y with [m]", "MAX h with [m]",
               "sigma x/y with [m]", "in 2sig with", "IP x/y [%]"},
              rows, markdown);
  std::printf("\nNetwork (with): %llu training samples, %llu valid predictions during outages, %llu pseudo-measurement axes fused\n",
              static_cast<unsigned long long>(samples), static_cast<unsigned long long>(predictions),
              static_cast<unsigned long long>(fused));
  return failed == 0 ? 0 : 1;
}

}  // namespace uwbnav::eval
