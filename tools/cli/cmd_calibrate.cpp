// `uwbnav calibrate RECORDING... --out FILE`: per anchor/tag pair range offsets
// from commissioning recordings, written as a site calibration file
// (tools/calib/, docs/commissioning.md).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tools/calib/calibrate.hpp"
#include "tools/cli/args.hpp"
#include "tools/dataset/calibration.hpp"
#include "tools/dataset/csv.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::cli {
namespace {

const char* const kUsage =
    "usage: uwbnav calibrate RECORDING... --out FILE [--method auto|truth|static|self]\n"
    "                        [--static-points FILE] [--knot-s S] [--z common|free|fixed] [--body-z M]\n"
    "                        [--common-offset M] [--max-sigma M] [--prior-sigma M] [--huber K] [--reject K]\n"
    "                        [--compare FILE]\n"
    "  method auto: truth.csv when every recording has one, else static points\n"
    "  (RECORDING/static_points.csv or --static-points), else self-calibration\n"
    "  --compare FILE: print the differences to another calibration file of the same site\n";

bool get_real(const Args& args, const char* key, double& out) {
  if (!args.has(key)) return true;
  const std::string v = args.get(key);
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(x)) {
    std::fprintf(stderr, "uwbnav calibrate: %s expects a number, got '%s'\n", key, v.c_str());
    return false;
  }
  out = x;
  return true;
}

// Per pair differences to a reference file (after and before removing the mean difference).
int compare(const std::string& path, const calib::Result& r) {
  std::string text;
  dataset::CalibrationFile ref;
  std::vector<std::string> errors;
  if (!ok(dataset::csv::read_file(path, text)) || !ok(dataset::parse_calibration(text, path, ref, errors)) ||
      !ok(dataset::check_calibration(ref, r.site, path, errors))) {
    for (const auto& e : errors) std::fprintf(stderr, "uwbnav calibrate: %s\n", e.c_str());
    std::fprintf(stderr, "uwbnav calibrate: cannot compare with %s\n", path.c_str());
    return 1;
  }
  std::vector<double> diff;
  std::printf("compare with %s (this minus reference):\n  anchor tag  offset_m  reference_m    diff_m  diff/sigma\n",
              path.c_str());
  for (const auto& p : r.pairs) {
    for (const auto& q : ref.pairs) {
      if (q.anchor_id != p.anchor_id || q.tag_id != p.tag_id) continue;
      const double d = p.offset_m - static_cast<double>(q.offset_m);
      diff.push_back(d);
      std::printf("  %6u %3u %9.4f %12.4f %9.4f %11.2f\n", static_cast<unsigned>(p.anchor_id),
                  static_cast<unsigned>(p.tag_id), p.offset_m, static_cast<double>(q.offset_m), d,
                  p.sigma_m > 0.0 ? d / p.sigma_m : 0.0);
    }
  }
  double mean = 0.0;
  for (double d : diff) mean += d;
  mean /= static_cast<double>(diff.size());
  double rms = 0.0;
  double mx = 0.0;
  double rms0 = 0.0;
  double mx0 = 0.0;
  for (double d : diff) {
    rms += d * d;
    mx = std::max(mx, std::fabs(d));
    rms0 += (d - mean) * (d - mean);
    mx0 = std::max(mx0, std::fabs(d - mean));
  }
  const double n = static_cast<double>(diff.size());
  std::printf("  difference: max %.4f m, rms %.4f m, mean %.4f m; without the mean (gauge): max %.4f m, rms %.4f m\n",
              mx, std::sqrt(rms / n), mean, mx0, std::sqrt(rms0 / n));
  return 0;
}

}  // namespace

int cmd_calibrate(int argc, char** argv) {
  Args args(argc, argv, {});
  const std::vector<std::string> known = {"--out",       "--method",    "--static-points", "--knot-s",
                                          "--z",         "--body-z",    "--common-offset", "--max-sigma",
                                          "--prior-sigma", "--huber",   "--reject",        "--compare"};
  if (!args.error().empty() || args.positional().empty() || !args.unknown(known).empty() ||
      (!args.has("--out") && !args.has("--compare"))) {
    std::fprintf(stderr, "%s", kUsage);
    return 2;
  }
  calib::Options opt;
  const std::string method = args.get("--method", "auto");
  if (method == "auto") {
    opt.method = args.has("--static-points") ? calib::Method::kStatic : calib::Method::kAuto;
  } else if (method == "truth") {
    opt.method = calib::Method::kTruth;
  } else if (method == "static") {
    opt.method = calib::Method::kStatic;
  } else if (method == "self") {
    opt.method = calib::Method::kSelf;
  } else {
    std::fprintf(stderr, "uwbnav calibrate: --method must be auto, truth, static or self\n%s", kUsage);
    return 2;
  }
  const std::string z = args.get("--z", "common");
  if (z == "common") {
    opt.z = calib::ZMode::kCommon;
  } else if (z == "free") {
    opt.z = calib::ZMode::kFree;
  } else if (z == "fixed") {
    opt.z = calib::ZMode::kFixed;
  } else {
    std::fprintf(stderr, "uwbnav calibrate: --z must be common, free or fixed\n");
    return 2;
  }
  if (!get_real(args, "--knot-s", opt.knot_s) || !get_real(args, "--body-z", opt.body_z_m) ||
      !get_real(args, "--max-sigma", opt.max_sigma_m) || !get_real(args, "--prior-sigma", opt.prior_sigma_m) ||
      !get_real(args, "--huber", opt.huber_k) || !get_real(args, "--reject", opt.reject_k) ||
      !get_real(args, "--common-offset", opt.common_offset_m)) {
    return 2;
  }
  opt.fix_common = args.has("--common-offset");
  if (!(opt.knot_s >= 0.0) || !(opt.max_sigma_m > 0.0) || !(opt.prior_sigma_m > 0.0) || !(opt.huber_k > 0.0) ||
      !(opt.reject_k > opt.huber_k)) {
    std::fprintf(stderr, "uwbnav calibrate: --knot-s >= 0 (0: auto), --max-sigma, --prior-sigma, --huber > 0, "
                         "--reject > --huber\n");
    return 2;
  }

  std::vector<dataset::Recording> recs(args.positional().size());
  std::vector<std::string> names;
  for (size_t i = 0; i < recs.size(); ++i) {
    const std::string& dir = args.positional()[i];
    dataset::ReadReport report;
    if (!ok(dataset::read_recording(dir, recs[i], report))) {
      std::fprintf(stderr, "uwbnav calibrate: cannot read %s: %s\n", dir.c_str(), report.error.c_str());
      return 1;
    }
    if (report.rows_skipped > 0) std::fprintf(stderr, "warning: %s: %zu bad rows skipped\n", dir.c_str(), report.rows_skipped);
    names.push_back(recs[i].name());
  }
  if (opt.method == calib::Method::kStatic || opt.method == calib::Method::kAuto) {
    if (args.has("--static-points") && recs.size() != 1) {
      std::fprintf(stderr, "uwbnav calibrate: --static-points takes one recording; with several, put a "
                           "static_points.csv in each recording directory\n");
      return 2;
    }
    std::vector<std::vector<calib::StaticPoint>> pts;
    for (size_t i = 0; i < recs.size(); ++i) {
      const std::string path =
          args.has("--static-points") ? args.get("--static-points") : args.positional()[i] + "/static_points.csv";
      std::vector<calib::StaticPoint> p;
      std::vector<std::string> errors;
      const Status s = calib::read_static_points(path, p, errors);
      if (s == Status::kNotFound && !args.has("--static-points") && opt.method == calib::Method::kAuto) break;
      if (!ok(s)) {
        for (const auto& e : errors) std::fprintf(stderr, "uwbnav calibrate: %s\n", e.c_str());
        return 1;
      }
      pts.push_back(p);
    }
    if (pts.size() == recs.size()) opt.static_points = pts;
  }

  calib::Result result;
  std::string err;
  if (!ok(calib::calibrate(recs, opt, result, &err))) {
    std::fprintf(stderr, "uwbnav calibrate: %s\n", err.c_str());
    return 1;
  }
  calib::print_report(stdout, result, opt);
  int rc = 0;
  if (args.has("--compare")) rc = compare(args.get("--compare"), result);
  if (!args.has("--out")) return rc;
  if (!result.observable) {
    std::fprintf(stderr, "uwbnav calibrate: not every offset is observable from these recordings; %s not written\n",
                 args.get("--out").c_str());
    return 1;
  }
  const dataset::CalibrationFile file = calib::to_calibration_file(result, names);
  if (!ok(dataset::write_calibration(args.get("--out"), file))) {
    std::fprintf(stderr, "uwbnav calibrate: cannot write %s\n", args.get("--out").c_str());
    return 1;
  }
  std::printf("wrote %s (%zu pairs, site_sigma_m %.4f)\n", args.get("--out").c_str(), file.pairs.size(),
              static_cast<double>(file.site_sigma_m));
  return rc;
}

}  // namespace uwbnav::cli
