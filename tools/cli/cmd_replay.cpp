// `uwbnav replay DIR --out OUT [--param name=value]... [--cal FILE]` and
// `uwbnav run` (the main job: simulate the default scenario, write it, replay it, print the table).
// The replay streams the recording from its directory and computes the table on the fly.
// Exit status: 0 a solution over complete input; 1 unreadable input or failure
// (nothing left in OUT); 2 usage or parameter error; 3 the replay ran but
// produced no solution or an input stream ended early (outputs kept).
#include <cstdio>
#include <string>

#include "tools/cli/args.hpp"
#include "tools/cli/cal_option.hpp"
#include "tools/dataset/fs.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/recording_stream.hpp"
#include "tools/dataset/tables.hpp"
#include "tools/eval/replay.hpp"
#include "tools/eval/summary.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::cli {
namespace {

constexpr int kExitIncomplete = 3;

// Streams the recording in `dir` through the firmware loop into `out`, with
// the result table computed on the fly (memory independent of the length).
int replay_and_report(const std::string& dir, const std::string& out, const Args& args, const char* who) {
  eval::ReplayOptions opt;
  opt.out_dir = out;
  opt.keep_in_memory = false;
  opt.progress = args.has("--progress");
  if (!parse_param_options(args, who, &opt.params)) return 2;
  dataset::RecordingStream rec;
  dataset::ReadReport report;
  if (!ok(rec.open(dir, report, false))) {
    std::fprintf(stderr, "%s: cannot read recording %s: %s\n", who, dir.c_str(), report.error.c_str());
    dataset::print_warnings(report, stderr);
    return 1;
  }
  if (!apply_cal_option(args, rec.site, who)) return 1;
  // The result table is built on the replay's output thread from readers of
  // its own: truth.csv (its warnings joined to the replay's afterwards) and
  // uwb.csv again (its warnings repeat the replay's and are not shown).
  dataset::RowStream<dataset::TruthRow> truth;
  dataset::ReadReport truth_report;
  dataset::RowStream<dataset::UwbRow> summary_uwb;
  dataset::ReadReport summary_report;
  if (!ok(truth.open(dir, "truth.csv", dataset::tables::kTruth, false, truth_report)) ||
      !ok(summary_uwb.open(dir, "uwb.csv", dataset::tables::kUwb, true, summary_report))) {
    const std::string& why = truth_report.error.empty() ? summary_report.error : truth_report.error;
    std::fprintf(stderr, "%s: cannot read recording %s: %s\n", who, dir.c_str(), why.c_str());
    return 1;
  }
  eval::SummaryBuilder summary(rec.site, rec.name(), summary_uwb, truth.present() ? &truth : nullptr);
  opt.sink = &summary;
  dataset::OutputDir out_dir;
  if (!out_dir.create(out)) {
    std::fprintf(stderr, "%s: cannot create %s\n", who, out.c_str());
    return 1;
  }
  eval::ReplayResult result;
  std::string err;
  const Status s = eval::run_replay(rec, opt, result, &err);
  if (!ok(s)) {
    std::fprintf(stderr, "%s: %s\n", who, err.c_str());
    return s == Status::kNotFound || s == Status::kOutOfRange ? 2 : 1;
  }
  const eval::RunSummary table = summary.finish(result);
  std::string read_error = rec.read_error();
  if (read_error.empty()) read_error = truth.error();
  for (const auto& w : truth_report.warnings) {
    if (report.warnings.size() < dataset::ReadReport::kMaxWarnings) {
      report.warnings.push_back(w);
    } else {
      ++report.warnings_dropped;
    }
  }
  report.warnings_dropped += truth_report.warnings_dropped;
  report.rows_skipped += truth_report.rows_skipped;
  dataset::print_warnings(report, stderr);
  if (report.rows_skipped > 0) std::fprintf(stderr, "warning: %zu bad rows skipped\n", report.rows_skipped);
  if (!read_error.empty()) {
    std::fprintf(stderr, "%s: cannot read recording %s: %s\n", who, dir.c_str(), read_error.c_str());
    return 1;
  }
  out_dir.keep();
  eval::print_summary(stdout, table);
  if (!rec.gnss.empty()) {
    // What became of the receiver's fixes (docs/ekf.md "GNSS"; per reason: console `stats gnss`).
    std::printf("gnss: %zu fixes in gnss.csv, %llu fused, %llu refused by the estimator, %lu refused by input validation\n",
                rec.gnss.size(), static_cast<unsigned long long>(result.gnss_fused),
                static_cast<unsigned long long>(result.gnss_rejected),
                static_cast<unsigned long>(result.stats.gnss.rejected_total()));
  }
#if UWBNAV_COOP
  if (result.stats.neighbours.received > 0 || result.diag.neighbour_ranges > 0) {
    // What became of the neighbours' states and the ranges to them (docs/ekf.md
    // "Neighbour ranges"; per reason: console `stats src=neighbours`, `stats coop`).
    uint64_t refused = 0;
    for (uint32_t n : result.diag.neighbour_rejected) refused += n;
    std::printf("neighbours: %lu states received, %lu refused by input validation; %lu ranges to vehicles, %lu fused, "
                "%llu refused by the estimator\n",
                static_cast<unsigned long>(result.stats.neighbours.received),
                static_cast<unsigned long>(result.stats.neighbours.rejected_total()),
                static_cast<unsigned long>(result.diag.neighbour_ranges),
                static_cast<unsigned long>(result.diag.neighbour_used), static_cast<unsigned long long>(refused));
  }
#endif
  std::printf("outputs: %s/{estimates.csv, ranges.csv, can.log}\n", out.c_str());
  int rc = 0;
  if (result.solution_epochs == 0) {
    std::fprintf(stderr, "%s: no solution: 0 of %llu epochs carry a position (%llu ranges used of %zu in uwb.csv)\n",
                 who, static_cast<unsigned long long>(result.epochs),
                 static_cast<unsigned long long>(result.ranges_used), rec.uwb.rows_delivered());
    rc = kExitIncomplete;
  }
  if (rec.imu.rows_delivered() > 0 && rec.uwb.rows_delivered() > 0) {
    for (const auto& line : dataset::streams_ended_early(rec.imu.last_t_us(), rec.uwb.last_t_us())) {
      std::fprintf(stderr, "%s: %s\n", who, line.c_str());
      rc = kExitIncomplete;
    }
  }
  return rc;
}

const char* const kReplayUsage =
    "usage: uwbnav replay DATASET_DIR --out OUT_DIR [--param name=value]... [--cal FILE] [--progress]\n"
    "  --param NAME=VALUE: overrides the parameter table (uwbnav params); wins over the site file\n"
    "  --cal FILE: site range calibration (uwbnav calibrate, docs/commissioning.md)\n"
    "  exit status: 0 solution over complete input, 1 unreadable input or failure (no OUT_DIR left),\n"
    "  2 usage or parameter error, 3 no solution (0 epochs) or an input stream ended early\n";

}  // namespace

int cmd_replay(int argc, char** argv) {
  Args args(argc, argv, {"--progress"});
  if (!args.error().empty() || args.positional().size() != 1 || !args.has("--out") ||
      !args.unknown({"--out", "--param", "--progress", "--cal"}).empty()) {
    std::fprintf(stderr, "%s", kReplayUsage);
    if (!args.error().empty()) std::fprintf(stderr, "uwbnav replay: %s\n", args.error().c_str());
    return 2;
  }
  std::vector<std::pair<std::string, float>> checked;
  if (!parse_param_options(args, "uwbnav replay", &checked)) return 2;
  return replay_and_report(args.positional()[0], args.get("--out"), args, "uwbnav replay");
}

int cmd_run(int argc, char** argv) {
  Args args(argc, argv, {"--progress"});
  uint64_t seed = 1;
  if (!args.error().empty() || args.positional().size() > 1 ||
      !args.unknown({"--out", "--seed", "--param", "--progress", "--cal"}).empty() ||
      !args.get_u64("--seed", 1, &seed)) {
    std::fprintf(stderr, "usage: uwbnav run [SCENARIO] [--out DIR] [--seed N] [--param name=value]... [--cal FILE]\n");
    if (!args.error().empty()) std::fprintf(stderr, "uwbnav run: %s\n", args.error().c_str());
    return 2;
  }
  std::vector<std::pair<std::string, float>> checked;
  if (!parse_param_options(args, "uwbnav run", &checked)) return 2;
  const std::string scenario = args.positional().empty() ? sim::preset_names().front() : args.positional()[0];
  const std::string out = args.get("--out", "out/run");
  dataset::Recording rec;
  std::string err;
  if (!ok(sim::simulate(scenario, seed, rec, &err))) {
    std::fprintf(stderr, "uwbnav run: %s\n", err.c_str());
    return 1;
  }
  dataset::OutputDir out_dir;
  const std::string rec_dir = out + "/recording";
  if (!out_dir.create(rec_dir) || !ok(dataset::write_recording(rec_dir, rec))) {
    std::fprintf(stderr, "uwbnav run: cannot write %s\n", rec_dir.c_str());
    return 1;
  }
  std::printf("scenario %s (seed %llu): %zu IMU samples, %zu ranges -> %s\n", scenario.c_str(),
              static_cast<unsigned long long>(seed), rec.imu.size(), rec.uwb.size(), rec_dir.c_str());
  const int rc = replay_and_report(rec_dir, out, args, "uwbnav run");
  if (rc != 1 && rc != 2) out_dir.keep();
  return rc;
}

}  // namespace uwbnav::cli
