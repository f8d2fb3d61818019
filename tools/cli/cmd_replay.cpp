// `uwbnav replay DIR --out OUT [--param name=value]... [--cal FILE]` and
// `uwbnav run` (the main job: simulate the default scenario, replay it, print the table).
#include <sys/stat.h>

#include <cerrno>

#include <cstdio>
#include <string>

#include "tools/cli/args.hpp"
#include "tools/cli/cal_option.hpp"
#include "tools/dataset/fs.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/eval/replay.hpp"
#include "tools/eval/summary.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::cli {
namespace {

int replay_and_report(const dataset::Recording& rec, const std::string& out, const Args& args) {
  eval::ReplayOptions opt;
  opt.out_dir = out;
  opt.progress = args.has("--progress");
  for (const auto& p : args.all("--param")) {
    std::pair<std::string, float> kv;
    if (!parse_param_override(p, &kv)) {
      std::fprintf(stderr, "uwbnav: --param expects name=value, got '%s'\n", p.c_str());
      return 2;
    }
    opt.params.push_back(kv);
  }
  if (!dataset::make_dirs(out)) {
    std::fprintf(stderr, "uwbnav: cannot create %s\n", out.c_str());
    return 1;
  }
  eval::ReplayResult result;
  std::string err;
  if (!ok(eval::run_replay(rec, opt, result, &err))) {
    std::fprintf(stderr, "uwbnav: %s\n", err.c_str());
    return 1;
  }
  eval::print_summary(stdout, eval::summarise(rec, result));
  std::printf("outputs: %s/{estimates.csv, ranges.csv, can.log}\n", out.c_str());
  return 0;
}

}  // namespace

int cmd_replay(int argc, char** argv) {
  Args args(argc, argv, {"--progress"});
  if (!args.error().empty() || args.positional().size() != 1 || !args.has("--out") ||
      !args.unknown({"--out", "--param", "--progress", "--cal"}).empty()) {
    std::fprintf(stderr,
                 "usage: uwbnav replay DATASET_DIR --out OUT_DIR [--param name=value]... [--cal FILE] [--progress]\n"
                 "  --cal FILE: site range calibration (uwbnav calibrate, docs/commissioning.md)\n");
    return 2;
  }
  dataset::Recording rec;
  dataset::ReadReport report;
  if (!ok(dataset::read_recording(args.positional()[0], rec, report))) {
    std::fprintf(stderr, "uwbnav replay: cannot read recording %s\n", args.positional()[0].c_str());
    for (const auto& w : report.warnings) std::fprintf(stderr, "  %s\n", w.c_str());
    return 1;
  }
  for (const auto& w : report.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (report.rows_skipped > 0) std::fprintf(stderr, "warning: %zu bad rows skipped\n", report.rows_skipped);
  if (!apply_cal_option(args, rec.site, "uwbnav replay")) return 1;
  return replay_and_report(rec, args.get("--out"), args);
}

int cmd_run(int argc, char** argv) {
  Args args(argc, argv, {"--progress"});
  uint64_t seed = 1;
  if (!args.error().empty() || args.positional().size() > 1 ||
      !args.unknown({"--out", "--seed", "--param", "--progress", "--cal"}).empty() ||
      !args.get_u64("--seed", 1, &seed)) {
    std::fprintf(stderr, "usage: uwbnav run [SCENARIO] [--out DIR] [--seed N] [--param name=value]... [--cal FILE]\n");
    return 2;
  }
  const std::string scenario = args.positional().empty() ? sim::preset_names().front() : args.positional()[0];
  const std::string out = args.get("--out", "out/run");
  dataset::Recording rec;
  std::string err;
  if (!ok(sim::simulate(scenario, seed, rec, &err))) {
    std::fprintf(stderr, "uwbnav run: %s\n", err.c_str());
    return 1;
  }
  const std::string rec_dir = out + "/recording";
  if (!dataset::make_dirs(rec_dir) || !ok(dataset::write_recording(rec_dir, rec))) {
    std::fprintf(stderr, "uwbnav run: cannot write %s\n", rec_dir.c_str());
    return 1;
  }
  std::printf("scenario %s (seed %llu): %zu IMU samples, %zu ranges -> %s\n", scenario.c_str(),
              static_cast<unsigned long long>(seed), rec.imu.size(), rec.uwb.size(), rec_dir.c_str());
  if (!apply_cal_option(args, rec.site, "uwbnav run")) return 1;
  return replay_and_report(rec, out, args);
}

}  // namespace uwbnav::cli
