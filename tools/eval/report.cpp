// `uwbnav eval report` (see report.hpp): every method over every recording,
// tables in the form of seed 000 Tables 2-5, series for the figures, figures.
#include "tools/dataset/fs.hpp"
#include "tools/eval/report.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <thread>
#include <tuple>

#include "estimator/gating.hpp"
#include "firmware/app.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/lockstep_clock.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "hal/host/replay_sources.hpp"
#include "tools/eval/baselines.hpp"
#include "tools/eval/replay.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::eval {
namespace {

struct PolicyRow {
  const char* name;
  const char* key;
  GatingPolicy policy;
};

// Table 3 rows that run the firmware (gate.policy), in report order.
constexpr PolicyRow kPolicies[] = {
    {"EKF, no gating", "ekf_none", GatingPolicy::kNone},
    {"EKF + innovation gate", "ekf_innovation", GatingPolicy::kInnovation},
    {"EKF + SVM (seed 000 1.2(1))", "ekf_svm", GatingPolicy::kSvm},
    {"EKF + consistency MC (eq. 3-6)", "ekf_mc", GatingPolicy::kConsistency},
    {"EKF + D-S fusion (eq. 7-8, 1.3)", "ekf_ds", GatingPolicy::kDempsterShafer},
    {"EKF + residual inflation (seed 003)", "ekf_resid", GatingPolicy::kResidualInflation},
    {"EKF + RAIM (seed 001)", "ekf_raim", GatingPolicy::kRaim},
    {"uwbnav default", "default", GatingPolicy::kDefault},
};

Confusion confusion_of(const dataset::Recording& rec, const std::vector<RangeReport>& ranges) {
  std::map<std::tuple<uint64_t, uint16_t, uint8_t>, int8_t> labels;
  for (const auto& u : rec.uwb) labels[{u.range.t_us, u.range.anchor_id, u.range.tag_id}] = u.nlos_label;
  Confusion c;
  for (const auto& r : ranges) {
    auto it = labels.find({r.t_us, r.anchor_id, r.tag_id});
    if (it == labels.end() || it->second < 0) continue;
    c.add(it->second == 1, r.nlos);
  }
  return c;
}

size_t epochs_in_truth(const dataset::Recording& rec, const std::vector<dataset::EstimateRow>& est) {
  size_t n = 0;
  double p[3];
  for (const auto& e : est) n += truth_at(rec.truth, e.t_us, p) ? 1 : 0;
  return n;
}

// UWB source that stops handing out ranges once `cut` is set: the IMU-only row
// (the filter initialises from UWB, then dead-reckons).
class CutUwbSource final : public hal::UwbSource {
 public:
  CutUwbSource(hal::UwbSource& inner, const bool& cut) : inner_(inner), cut_(cut) {}
  Status poll(uint64_t up_to_us, UwbRange& out) override {
    const Status s = inner_.poll(up_to_us, out);
    return ok(s) && cut_ ? Status::kEmpty : s;
  }
  bool finished() const override { return inner_.finished(); }

 private:
  hal::UwbSource& inner_;
  const bool& cut_;
};

MethodResult run_policy(const dataset::Recording& rec, const PolicyRow& row) {
  MethodResult m;
  m.name = row.name;
  m.key = row.key;
  ReplayOptions opt;
  opt.params.push_back({"gate.policy", static_cast<float>(row.policy)});
  ReplayResult res;
  std::string err;
  if (!ok(run_replay(rec, opt, res, &err))) {
    std::fprintf(stderr, "eval: %s on %s: %s\n", row.name, rec.name().c_str(), err.c_str());
    return m;
  }
  m.errors = compare_with_truth(res.estimates, rec.truth);
  m.acc = accuracy(m.errors, epochs_in_truth(rec, res.estimates));
  m.has_nlos = row.policy != GatingPolicy::kNone;
  m.nlos = confusion_of(rec, res.ranges);
  m.us_per_cycle = res.cycles ? 1e6 * res.wall_s / static_cast<double>(res.cycles) : 0.0;
  m.ranges_used = res.ranges_used;
  m.ranges_rejected = res.ranges_rejected;
  m.estimates = std::move(res.estimates);
  return m;
}

MethodResult run_ls(const dataset::Recording& rec, LsMethod method) {
  MethodResult m;
  m.name = method == LsMethod::kLinear ? "LS-UWB (linear LS)" : "LS-Taylor (seed 003 eq. 1-4)";
  m.key = method == LsMethod::kLinear ? "ls_uwb" : "ls_taylor";
  const auto t0 = std::chrono::steady_clock::now();
  auto est = ls_baseline(rec, method);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto truth = tag_truth(rec);
  m.errors = compare_with_truth(est, truth);
  size_t total = 0;
  double p[3];
  if (!est.empty()) {
    for (uint64_t t = est.front().t_us; t <= est.back().t_us; t += 10000) total += truth_at(truth, t, p) ? 1 : 0;
  }
  m.acc = accuracy(m.errors, std::max(total, m.errors.size()));
  m.us_per_cycle = est.empty() ? 0.0 : 1e6 * wall / static_cast<double>(est.size());
  m.estimates = std::move(est);
  return m;
}

// IMU only: the default filter initialises on UWB, then ranges are withheld.
MethodResult run_imu_only(const dataset::Recording& rec) {
  MethodResult m;
  m.name = "IMU only (after UWB initialisation)";
  m.key = "imu_only";
  if (rec.imu.empty()) return m;
  bool cut = false;
  hal::ReplaySources sources(rec);
  CutUwbSource uwb(sources.uwb, cut);
  hal::LockstepClock clock;
  hal::MemCanBus bus;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{sources.imu, uwb, bus, serial, clock, store, rec.site, sources.gnss_or_null(rec),
                   sources.neighbours_or_null(rec)};
  App app(board);
  if (!ok(app.init())) return m;
  std::vector<dataset::EstimateRow> est;
  uint64_t t = ((rec.imu.front().t_us) / kCyclePeriodUs + 1) * kCyclePeriodUs;
  const auto t0 = std::chrono::steady_clock::now();
  uint64_t cycles = 0;
  while (!(sources.imu.finished() && sources.uwb.finished())) {
    clock.sleep_until_us(t);
    app.tick(t);
    hal::CanFrame f;
    while (ok(bus.receive_sent(f))) {
    }
    if (app.last_output().status == NavStatus::kValid) cut = true;
    if (cut) est.push_back(to_estimate_row(app.last_output()));
    t += kCyclePeriodUs;
    ++cycles;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  m.errors = compare_with_truth(est, rec.truth);
  m.acc = accuracy(m.errors, epochs_in_truth(rec, est));
  m.us_per_cycle = cycles ? 1e6 * wall / static_cast<double>(cycles) : 0.0;
  m.estimates = std::move(est);
  return m;
}

// Fixed-point text of v, "n/a" when not a number (no solution / undefined ratio).
std::string num(double v, int digits = 3) {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}
std::string pct(double v) { return std::isfinite(v) ? num(100.0 * v, 2) + " %" : "n/a"; }

void write_md_tables(std::FILE* f, const RecordingReport& r) {
  std::fprintf(f, "### %s\n\n", r.name.c_str());
  std::fprintf(f, "Source `%s`: %.1f s, %zu IMU samples, %zu ranges, %zu labelled NLOS.\n\n", r.source.c_str(),
               r.duration_s, r.imu_samples, r.ranges, r.nlos_labelled);
  std::fprintf(f, "Positioning (seed 000 Table 3 form; horizontal error of epochs with a solution):\n\n");
  std::fprintf(f, "| method | RMSE [m] | MAX [m] | STD [m] | availability | in 2σ x / y | ranges used / rejected |\n");
  std::fprintf(f, "|---|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& m : r.methods) {
    const double avail = m.acc.epochs_total ? 100.0 * static_cast<double>(m.acc.epochs) / static_cast<double>(m.acc.epochs_total) : 0.0;
    std::fprintf(f, "| %s | %s | %s | %s | %.1f %% |", m.name.c_str(), num(m.acc.rmse_h_m).c_str(),
                 num(m.acc.max_h_m).c_str(), num(m.acc.std_h_m).c_str(), avail);
    if (m.key.rfind("ls_", 0) == 0 || m.key == "imu_only") {
      std::fprintf(f, " - | - |\n");
    } else {
      std::fprintf(f, " %s / %s | %llu / %llu |\n", pct(m.acc.inside_2sigma_x).c_str(), pct(m.acc.inside_2sigma_y).c_str(),
                   static_cast<unsigned long long>(m.ranges_used), static_cast<unsigned long long>(m.ranges_rejected));
    }
  }
  std::fprintf(f, "\nError distribution (seed 000 Table 4 form; |east| = |x error|, |north| = |y error|) [m]:\n\n");
  std::fprintf(f, "| method | 50 %% E | 50 %% N | 70 %% E | 70 %% N | 90 %% E | 90 %% N |\n|---|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& m : r.methods) {
    std::fprintf(f, "| %s | %s | %s | %s | %s | %s | %s |\n", m.name.c_str(), num(m.acc.p50_east_m).c_str(),
                 num(m.acc.p50_north_m).c_str(), num(m.acc.p70_east_m).c_str(), num(m.acc.p70_north_m).c_str(),
                 num(m.acc.p90_east_m).c_str(), num(m.acc.p90_north_m).c_str());
  }
  bool any_labels = false;
  for (const auto& m : r.methods) any_labels |= m.has_nlos && m.nlos.n() > 0;
  if (any_labels) {
    std::fprintf(f, "\nNLOS decisions against the recording's labels (seed 000 Table 2 form, eq. 11-13):\n\n");
    std::fprintf(f, "| method | precision | recall | accuracy | ranges |\n|---|---:|---:|---:|---:|\n");
    for (const auto& m : r.methods) {
      if (!m.has_nlos || m.nlos.n() == 0) continue;
      std::fprintf(f, "| %s | %s | %s | %s | %llu |\n", m.name.c_str(), pct(m.nlos.precision()).c_str(),
                   pct(m.nlos.recall()).c_str(), pct(m.nlos.accuracy()).c_str(), static_cast<unsigned long long>(m.nlos.n()));
    }
  }
  std::fprintf(f, "\nTime per 10 ms cycle on this host (seed 000 Table 5 analog, whole firmware loop incl. I/O-free replay):\n\n");
  std::fprintf(f, "| method | µs per cycle |\n|---|---:|\n");
  for (const auto& m : r.methods) std::fprintf(f, "| %s | %.2f |\n", m.name.c_str(), m.us_per_cycle);
  std::fprintf(f, "\n");
}

void write_csv_tables(const std::string& path, const RecordingReport& r) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return;
  std::fprintf(f, "recording,method,rmse_m,max_m,std_m,epochs,epochs_total,in2s_x,in2s_y,p50_e,p50_n,p70_e,p70_n,p90_e,p90_n,"
                  "nlos_precision,nlos_recall,nlos_accuracy,nlos_n,us_per_cycle,ranges_used,ranges_rejected\n");
  for (const auto& m : r.methods) {
    std::fprintf(f, "%s,%s,%.6f,%.6f,%.6f,%zu,%zu,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,", r.name.c_str(), m.key.c_str(),
                 m.acc.rmse_h_m, m.acc.max_h_m, m.acc.std_h_m, m.acc.epochs, m.acc.epochs_total, m.acc.inside_2sigma_x,
                 m.acc.inside_2sigma_y, m.acc.p50_east_m, m.acc.p50_north_m, m.acc.p70_east_m, m.acc.p70_north_m,
                 m.acc.p90_east_m, m.acc.p90_north_m);
    if (m.has_nlos && m.nlos.n() > 0) {
      std::fprintf(f, "%.6f,%.6f,%.6f,%llu,", m.nlos.precision(), m.nlos.recall(), m.nlos.accuracy(),
                   static_cast<unsigned long long>(m.nlos.n()));
    } else {
      std::fprintf(f, ",,,,");
    }
    std::fprintf(f, "%.3f,%llu,%llu\n", m.us_per_cycle, static_cast<unsigned long long>(m.ranges_used),
                 static_cast<unsigned long long>(m.ranges_rejected));
  }
  std::fclose(f);
}

// Series for the figures: one CSV per method (errors, sigmas, positions),
// the truth track, the anchors, NLOS periods and UWB outages.
void write_series(const std::string& dir, const RecordingReport& r, const dataset::Recording& rec) {
  for (const auto& m : r.methods) {
    std::FILE* f = std::fopen((dir + "/series_" + m.key + ".csv").c_str(), "w");
    if (f == nullptr) continue;
    std::fprintf(f, "t_s,ex_m,ey_m,sx_m,sy_m,status\n");
    for (const auto& e : m.errors) {
      std::fprintf(f, "%.3f,%.4f,%.4f,%.4f,%.4f,%d\n", dataset::us_to_seconds(e.t_us), e.err_nav_m[0], e.err_nav_m[1],
                   e.sigma_nav_m[0], e.sigma_nav_m[1], e.status);
    }
    std::fclose(f);
    f = std::fopen((dir + "/track_" + m.key + ".csv").c_str(), "w");
    if (f == nullptr) continue;
    std::fprintf(f, "t_s,x_m,y_m\n");
    for (size_t i = 0; i < m.estimates.size(); i += 5) {
      const auto& e = m.estimates[i];
      if (e.status == 1 || e.status == 2) {
        std::fprintf(f, "%.3f,%.4f,%.4f\n", dataset::us_to_seconds(e.t_us), e.pos_nav_m[0], e.pos_nav_m[1]);
      }
    }
    std::fclose(f);
  }
  std::FILE* f = std::fopen((dir + "/track_truth.csv").c_str(), "w");
  if (f != nullptr) {
    std::fprintf(f, "t_s,x_m,y_m\n");
    for (const auto& t : rec.truth) std::fprintf(f, "%.3f,%.4f,%.4f\n", dataset::us_to_seconds(t.t_us), t.pos_nav_m[0], t.pos_nav_m[1]);
    std::fclose(f);
  }
  f = std::fopen((dir + "/anchors.csv").c_str(), "w");
  if (f != nullptr) {
    std::fprintf(f, "anchor_id,x_m,y_m\n");
    for (size_t i = 0; i < rec.site.num_anchors; ++i) {
      std::fprintf(f, "%u,%.3f,%.3f\n", rec.site.anchors[i].id, static_cast<double>(rec.site.anchors[i].pos_nav_m.x),
                   static_cast<double>(rec.site.anchors[i].pos_nav_m.y));
    }
    std::fclose(f);
  }
  // Periods: NLOS = a labelled NLOS range within 0.2 s; outage = no range for > 1 s.
  f = std::fopen((dir + "/periods.csv").c_str(), "w");
  if (f != nullptr) {
    std::fprintf(f, "kind,t0_s,t1_s\n");
    bool open = false;
    uint64_t a = 0, b = 0;
    for (const auto& u : rec.uwb) {
      if (u.nlos_label != 1) continue;
      if (open && u.range.t_us - b <= 200000) {
        b = u.range.t_us;
        continue;
      }
      if (open) std::fprintf(f, "nlos,%.3f,%.3f\n", dataset::us_to_seconds(a), dataset::us_to_seconds(b));
      open = true;
      a = b = u.range.t_us;
    }
    if (open) std::fprintf(f, "nlos,%.3f,%.3f\n", dataset::us_to_seconds(a), dataset::us_to_seconds(b));
    for (size_t i = 1; i < rec.uwb.size(); ++i) {
      const uint64_t gap = rec.uwb[i].range.t_us - rec.uwb[i - 1].range.t_us;
      if (gap > 1000000) {
        std::fprintf(f, "outage,%.3f,%.3f\n", dataset::us_to_seconds(rec.uwb[i - 1].range.t_us),
                     dataset::us_to_seconds(rec.uwb[i].range.t_us));
      }
    }
    std::fclose(f);
  }
}

std::string sanitize(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-') ? c : '_';
  return o;
}

}  // namespace

Status load_recording_spec(const std::string& spec, dataset::Recording& rec, std::string* error) {
  if (spec.rfind("sim:", 0) == 0) {
    std::string name = spec.substr(4);
    uint64_t seed = 1;
    const size_t colon = name.find(':');
    if (colon != std::string::npos) {
      seed = std::strtoull(name.c_str() + colon + 1, nullptr, 10);
      name = name.substr(0, colon);
    }
    const Status s = sim::simulate(name, seed, rec, error);
    if (ok(s)) rec.meta["name"] = name + "_seed" + std::to_string(seed);
    return s;
  }
  dataset::ReadReport rep;
  const Status s = dataset::read_recording(spec, rec, rep);
  if (!ok(s) && error) *error = "cannot read " + spec + (rep.error.empty() ? "" : ": " + rep.error);
  return s;
}

RecordingReport evaluate_recording(const dataset::Recording& rec, const std::string& source) {
  RecordingReport r;
  r.name = rec.name();
  r.source = source;
  r.imu_samples = rec.imu.size();
  r.ranges = rec.uwb.size();
  for (const auto& u : rec.uwb) r.nlos_labelled += u.nlos_label == 1 ? 1 : 0;
  if (!rec.uwb.empty()) r.duration_s = dataset::us_to_seconds(rec.uwb.back().range.t_us - rec.uwb.front().range.t_us);
  if (!rec.imu.empty()) r.methods.push_back(run_imu_only(rec));
  r.methods.push_back(run_ls(rec, LsMethod::kLinear));
  r.methods.push_back(run_ls(rec, LsMethod::kTaylor));
  for (const auto& p : kPolicies) r.methods.push_back(run_policy(rec, p));
  return r;
}

Status write_recording_report(const RecordingReport& r, const std::string& dir, bool figures) {
  if (!dataset::make_dirs(dir)) return Status::kIoError;
  std::FILE* f = std::fopen((dir + "/tables.md").c_str(), "w");
  if (f == nullptr) return Status::kIoError;
  write_md_tables(f, r);
  std::fclose(f);
  write_csv_tables(dir + "/tables.csv", r);
  (void)figures;
  return Status::kOk;
}

int run_eval_report(int argc, char** argv) {
  std::vector<std::string> specs;
  std::string out;
  unsigned jobs = std::max(1U, std::thread::hardware_concurrency());
  bool figures = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else if (a == "--jobs" && i + 1 < argc) {
      jobs = static_cast<unsigned>(std::max(1L, std::strtol(argv[++i], nullptr, 10)));
    } else if (a == "--no-figures") {
      figures = false;
    } else if (a == "--help") {
      specs.clear();
      break;
    } else if (a.rfind("--", 0) == 0) {
      std::fprintf(stderr, "uwbnav eval report: unknown option %s\n", a.c_str());
      return 2;
    } else {
      specs.push_back(a);
    }
  }
  if (specs.empty() || out.empty()) {
    std::fprintf(stderr, "usage: uwbnav eval report RECORDING... --out DIR [--jobs N] [--no-figures]\n"
                         "  RECORDING: a format v1 directory, or sim:PRESET[:SEED]\n"
                         "  exit status: 0 every recording evaluated over complete input, 1 a recording could not be\n"
                         "  evaluated, 2 usage error, 3 an input stream ended early (e.g. a truncated imu.csv; tables written)\n");
    return 2;
  }
  dataset::OutputDir out_dir;  // removed again when no recording could be evaluated
  if (!out_dir.create(out)) {
    std::fprintf(stderr, "uwbnav eval report: cannot create %s\n", out.c_str());
    return 1;
  }
  std::vector<RecordingReport> reports(specs.size());
  std::vector<std::string> errors(specs.size());
  std::vector<dataset::Recording> recs(specs.size());
  std::atomic<size_t> next{0};
  std::atomic<size_t> done{0};
  std::mutex print_mutex;
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  const auto t0 = std::chrono::steady_clock::now();
  auto progress = [&]() {
    std::lock_guard<std::mutex> lock(print_mutex);
    const size_t d = done.load();
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (tty) {
      const int width = 30;
      const int filled = static_cast<int>(width * d / specs.size());
      std::fprintf(stderr, "\r[%.*s%*s] %zu/%zu recordings %.0f s", filled, "##############################",
                   width - filled, "", d, specs.size(), el);
    } else {
      std::fprintf(stderr, "eval: %zu/%zu recordings done after %.0f s\n", d, specs.size(), el);
    }
  };
  auto worker = [&]() {
    for (;;) {
      const size_t i = next.fetch_add(1);
      if (i >= specs.size()) return;
      if (ok(load_recording_spec(specs[i], recs[i], &errors[i]))) {
        reports[i] = evaluate_recording(recs[i], specs[i]);
      } else if (errors[i].empty()) {
        errors[i] = "cannot load " + specs[i];
      }
      ++done;
      progress();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned j = 0; j < std::min<size_t>(jobs, specs.size()); ++j) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (tty) std::fprintf(stderr, "\n");

  // Merge in input order: the output does not depend on scheduling.
  std::FILE* md = std::fopen((out + "/results.md").c_str(), "w");
  if (md == nullptr) return 1;
  std::fprintf(md, "# uwbnav evaluation results\n\nGenerated by `uwbnav eval report");
  for (const auto& s : specs) std::fprintf(md, " %s", s.c_str());
  std::fprintf(md, " --out %s` — do not edit.\n\n", out.c_str());
  int failures = 0;
  for (size_t i = 0; i < specs.size(); ++i) {
    if (!errors[i].empty() && reports[i].methods.empty()) {
      std::fprintf(stderr, "eval: %s\n", errors[i].c_str());
      std::fprintf(md, "### %s\n\nnot evaluated: %s\n\n", specs[i].c_str(), errors[i].c_str());
      ++failures;
      continue;
    }
    const std::string dir = out + "/" + sanitize(reports[i].name);
    if (!ok(write_recording_report(reports[i], dir, figures))) {
      std::fprintf(stderr, "eval: cannot write %s\n", dir.c_str());
      ++failures;
      continue;
    }
    write_series(dir, reports[i], recs[i]);
    write_md_tables(md, reports[i]);
    if (figures) {
      const std::string cmd = "/usr/bin/python3 '" + std::string(UWBNAV_SOURCE_DIR) + "/tools/plot/report_plots.py' '" + dir + "'";
      if (std::system(cmd.c_str()) != 0) {
        std::fprintf(stderr, "eval: figures for %s not drawn (python3-matplotlib missing?)\n", reports[i].name.c_str());
      } else {
        std::fprintf(md, "Figures: `%s/` (trajectories.png, cdf_east_north.png, error_time.png, sigma_band.png)\n\n",
                     sanitize(reports[i].name).c_str());
      }
    }
  }
  std::fclose(md);
  // An input stream that ended early (a truncated imu.csv, a sensor that died)
  // leaves the tables standing but the run incomplete: exit 3, as `uwbnav replay`.
  size_t incomplete = 0;
  for (size_t i = 0; i < specs.size(); ++i) {
    if (reports[i].methods.empty()) continue;
    for (const auto& line : dataset::streams_ended_early(recs[i])) {
      std::fprintf(stderr, "uwbnav eval report: %s: %s\n", specs[i].c_str(), line.c_str());
      ++incomplete;
    }
  }
  if (static_cast<size_t>(failures) < specs.size()) out_dir.keep();
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("eval report: %zu recording(s), %d failed, %.1f s -> %s/results.md\n", specs.size(), failures, el,
              out.c_str());
  if (failures > 0) return 1;
  return incomplete > 0 ? 3 : 0;
}

}  // namespace uwbnav::eval
