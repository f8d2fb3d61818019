// `uwbnav eval nlos`: seed 000 Table 2 / Table 3 style evaluation of the NLOS gating policies.
#include "tools/eval/eval_nlos.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <sstream>
#include <tuple>

#include "estimator/nlos/channel.hpp"
#include "tools/eval/baselines.hpp"
#include "tools/eval/eval_family.hpp"
#include "tools/eval/replay.hpp"
#include "tools/eval/svm_features.hpp"
#include "tools/eval/svm_train.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::eval {

void Confusion::add(bool truth_nlos, bool said_nlos) {
  if (truth_nlos && said_nlos) ++tp;
  if (!truth_nlos && said_nlos) ++fp;
  if (!truth_nlos && !said_nlos) ++tn;
  if (truth_nlos && !said_nlos) ++fn;
}

void Confusion::add(const Confusion& o) {
  tp += o.tp;
  fp += o.fp;
  tn += o.tn;
  fn += o.fn;
}

double Confusion::precision() const {
  return tp + fp == 0 ? std::nan("") : static_cast<double>(tp) / static_cast<double>(tp + fp);
}
double Confusion::recall() const {
  return tp + fn == 0 ? std::nan("") : static_cast<double>(tp) / static_cast<double>(tp + fn);
}
double Confusion::false_alarm_rate() const {
  return fp + tn == 0 ? std::nan("") : static_cast<double>(fp) / static_cast<double>(fp + tn);
}
double Confusion::accuracy() const {
  return n() == 0 ? std::nan("") : static_cast<double>(tp + tn) / static_cast<double>(n());
}

std::vector<NlosMethod> nlos_methods() {
  return {
      {"EKF, no gating", GatingPolicy::kNone, {}},
      {"SVM1 (range rate)", GatingPolicy::kSvm, {{"gate.svm_model", 1.0F}}},
      {"SVM2 (range rate + speed)", GatingPolicy::kSvm, {{"gate.svm_model", 2.0F}}},
      {"MC (consistency, eq. 3-6)", GatingPolicy::kConsistency, {}},
      {"D-S fusion (eq. 7-8, 1.3)", GatingPolicy::kDempsterShafer, {}},
      {"RAIM (seed 001)", GatingPolicy::kRaim, {}},
      {"innovation gate", GatingPolicy::kInnovation, {}},
      {"residual inflation (seed 003)", GatingPolicy::kResidualInflation, {}},
      {"default", GatingPolicy::kDefault, {}},
  };
}

namespace {

using RangeKey = std::tuple<uint64_t, uint16_t, uint8_t>;

std::map<RangeKey, size_t> index_ranges(const dataset::Recording& rec) {
  std::map<RangeKey, size_t> idx;
  for (size_t i = 0; i < rec.uwb.size(); ++i) {
    const UwbRange& r = rec.uwb[i].range;
    idx.emplace(RangeKey{r.t_us, r.anchor_id, r.tag_id}, i);
  }
  return idx;
}

std::vector<size_t> labelled(const dataset::Recording& rec) {
  std::vector<size_t> out;
  for (size_t i = 0; i < rec.uwb.size(); ++i) {
    if (rec.uwb[i].nlos_label >= 0) out.push_back(i);
  }
  return out;
}

// Stratified random `fraction` of the labelled ranges (the paper's 30 % test split).
std::vector<size_t> test_split(const dataset::Recording& rec, double fraction, uint64_t seed) {
  std::vector<size_t> by_label[2];
  for (size_t i : labelled(rec)) by_label[rec.uwb[i].nlos_label > 0 ? 1 : 0].push_back(i);
  std::mt19937_64 rng(seed);
  std::vector<size_t> out;
  for (auto& v : by_label) {
    std::shuffle(v.begin(), v.end(), rng);
    const size_t k = static_cast<size_t>(std::llround(fraction * static_cast<double>(v.size())));
    out.insert(out.end(), v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k));
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string pct(double v) {
  if (!std::isfinite(v)) return "n/a";
  char b[32];
  std::snprintf(b, sizeof(b), "%.2f", 100.0 * v);
  return b;
}

std::string meters(double v) {
  if (!std::isfinite(v)) return "n/a";
  char b[32];
  std::snprintf(b, sizeof(b), "%.3f", v);
  return b;
}

void print_confusion_row(const std::string& name, const Confusion& c) {
  if (c.n() == 0) {
    std::printf("| %-38s | %9s | %9s | %9s | %7s |\n", name.c_str(), "n/a", "n/a", "n/a", "0");
    return;
  }
  std::printf("| %-38s | %9s | %9s | %9s | %7zu |\n", name.c_str(), pct(c.precision()).c_str(),
              pct(c.recall()).c_str(), pct(c.accuracy()).c_str(), c.n());
}

void print_confusion_header() {
  std::printf("| %-38s | %9s | %9s | %9s | %7s |\n", "method", "precision", "recall", "accuracy", "ranges");
  std::printf("|%s|%s|%s|%s|%s|\n", std::string(40, '-').c_str(), std::string(11, '-').c_str(),
              std::string(11, '-').c_str(), std::string(11, '-').c_str(), std::string(9, '-').c_str());
}

void print_position_header() {
  std::printf("| %-38s | %8s | %8s | %8s | %8s |\n", "method", "RMSE [m]", "MAX [m]", "STD [m]", "epochs");
  std::printf("|%s|%s|%s|%s|%s|\n", std::string(40, '-').c_str(), std::string(10, '-').c_str(),
              std::string(10, '-').c_str(), std::string(10, '-').c_str(), std::string(10, '-').c_str());
}

void print_position_row(const std::string& name, const std::vector<ErrorSample>& errors, size_t epochs_total) {
  const AccuracyStats a = accuracy(errors, epochs_total);
  std::printf("| %-38s | %8s | %8s | %8s | %8zu |\n", name.c_str(), meters(a.rmse_h_m).c_str(),
              meters(a.max_h_m).c_str(), meters(a.std_h_m).c_str(), a.epochs);
}

// Channel rule (first-path vs received power gap) on the ranges that carry diagnostics.
Confusion channel_rule(const dataset::Recording& rec, const std::vector<size_t>& subset) {
  Confusion c;
  for (size_t i : subset) {
    const dataset::UwbRow& row = rec.uwb[i];
    const float p = channel_p_nlos(row.range.fp_power_dbm, row.range.rx_power_dbm, 6.0F, 10.0F, 0.9F);
    if (!std::isfinite(p) || row.nlos_label < 0) continue;
    c.add(row.nlos_label > 0, p > 0.5F);
  }
  return c;
}

std::vector<uint64_t> parse_seeds(const std::string& s) {
  std::vector<uint64_t> out;
  std::istringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) {
    if (!tok.empty()) out.push_back(std::strtoull(tok.c_str(), nullptr, 10));
  }
  return out;
}

struct SetResult {
  std::vector<Confusion> confusion;                // per method
  std::vector<std::vector<ErrorSample>> errors;    // per method
  Confusion channel;
  std::vector<ErrorSample> ls_linear;
  std::vector<ErrorSample> ls_taylor;
  std::vector<ErrorSample> imu_only;
  size_t epochs_total = 0;
  size_t ranges = 0;
  size_t nlos_ranges = 0;
};

// Scores every method on one recording (subset = test split or all labelled).
bool evaluate_recording(const dataset::Recording& rec, const std::vector<size_t>& subset, bool positioning,
                        SetResult& acc) {
  const std::vector<NlosMethod> methods = nlos_methods();
  if (acc.confusion.empty()) {
    acc.confusion.resize(methods.size());
    acc.errors.resize(methods.size());
  }
  for (size_t i : subset.empty() ? labelled(rec) : subset) {
    ++acc.ranges;
    if (rec.uwb[i].nlos_label > 0) ++acc.nlos_ranges;
  }
  for (size_t m = 0; m < methods.size(); ++m) {
    Confusion c;
    std::vector<ErrorSample> err;
    std::string e;
    if (!ok(score_method(rec, methods[m], subset, c, positioning ? &err : nullptr, &e))) {
      std::fprintf(stderr, "uwbnav eval nlos: %s: %s\n", methods[m].name.c_str(), e.c_str());
      return false;
    }
    acc.confusion[m].add(c);
    acc.errors[m].insert(acc.errors[m].end(), err.begin(), err.end());
    std::fprintf(stderr, "  %-38s acc %s\n", methods[m].name.c_str(), pct(c.accuracy()).c_str());
  }
  acc.channel.add(channel_rule(rec, subset.empty() ? labelled(rec) : subset));
  if (positioning && !rec.truth.empty()) {
    const std::vector<dataset::TruthRow> tt = tag_truth(rec);
    const auto lin = compare_with_truth(ls_baseline(rec, LsMethod::kLinear), tt);
    const auto tay = compare_with_truth(ls_baseline(rec, LsMethod::kTaylor), tt);
    acc.ls_linear.insert(acc.ls_linear.end(), lin.begin(), lin.end());
    acc.ls_taylor.insert(acc.ls_taylor.end(), tay.begin(), tay.end());
    // IMU only: ranges for the first 30 s (initialisation, convergence), then dead reckoning.
    dataset::Recording cut = rec;
    const uint64_t t_cut = rec.uwb.empty() ? 0 : rec.uwb.front().range.t_us + 30000000U;
    cut.uwb.erase(std::remove_if(cut.uwb.begin(), cut.uwb.end(),
                                 [t_cut](const dataset::UwbRow& r) { return r.range.t_us > t_cut; }),
                  cut.uwb.end());
    ReplayOptions ro;
    ReplayResult rr;
    std::string e;
    if (ok(run_replay(cut, ro, rr, &e))) {
      const auto imu = compare_with_truth(rr.estimates, rec.truth);
      acc.imu_only.insert(acc.imu_only.end(), imu.begin(), imu.end());
    }
    acc.epochs_total += static_cast<size_t>((rec.truth.back().t_us - rec.truth.front().t_us) / 10000U);
  }
  return true;
}

void print_set(const char* title, const SetResult& r, bool positioning) {
  const std::vector<NlosMethod> methods = nlos_methods();
  std::printf("\n%s\n", title);
  std::printf("%zu scored ranges, %.1f %% labelled NLOS\n\n", r.ranges,
              r.ranges == 0 ? 0.0 : 100.0 * static_cast<double>(r.nlos_ranges) / static_cast<double>(r.ranges));
  print_confusion_header();
  for (size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].policy == GatingPolicy::kNone) continue;
    print_confusion_row(methods[m].name, r.confusion[m]);
  }
  print_confusion_row("channel rule (rx-fp > 6 dB)", r.channel);
  if (!positioning) return;
  std::printf("\nPositioning (seed 000 Table 3 form), horizontal error of the body origin (LS: tag antenna)\n\n");
  print_position_header();
  print_position_row("IMU only (UWB cut after 30 s)", r.imu_only, r.epochs_total);
  print_position_row("LS-UWB (linear LS)", r.ls_linear, r.epochs_total);
  print_position_row("LS-Taylor", r.ls_taylor, r.epochs_total);
  for (size_t m = 0; m < methods.size(); ++m) {
    const std::string name = methods[m].policy == GatingPolicy::kNone ? methods[m].name : "EKF + " + methods[m].name;
    print_position_row(name, r.errors[m], r.epochs_total);
  }
}

// (c): cross-validated channel SVM on a feature table; grouped folds hold whole positions out.
void evaluate_table(const std::string& path, int folds, uint64_t seed, size_t max_samples) {
  std::vector<SvmSample> samples;
  std::string err;
  if (!ok(samples_from_table(path, SvmFeatureSet::kChannel, samples, &err))) {
    std::printf("\n(c) %s: skipped (%s)\n", path.c_str(), err.c_str());
    return;
  }
  const std::vector<SvmSample> sub = stratified_subsample(samples, max_samples, seed);
  std::printf("\n(c) real labelled channel features: %s\n", path.c_str());
  std::printf("%zu labelled ranges (%zu used, stratified subsample); features rx-fp gap [dB], fp power [dBm];"
              " %d-fold cross-validation, C/gamma chosen by an inner grid search\n\n",
              samples.size(), sub.size(), folds);
  print_confusion_header();
  for (bool grouped : {false, true}) {
    SvmTrainOptions opt;
    opt.set = SvmFeatureSet::kChannel;
    opt.folds = folds;
    opt.grouped_cv = grouped;
    opt.grid_samples = std::min<size_t>(sub.size(), 1500);
    opt.max_train_samples = 1500;
    opt.seed = seed;
    SvmModel model;
    SvmTrainReport rep;
    if (!ok(train_svm_model(sub, opt, model, rep, &err))) {
      std::printf("| channel SVM, %s: %s |\n", grouped ? "positions held out" : "random folds", err.c_str());
      continue;
    }
    std::vector<int> pred;
    if (!ok(cross_validate(sub, SvmFeatureSet::kChannel, rep.best_c, rep.best_gamma, folds, grouped, false, seed + 5U,
                           &pred, nullptr, &err))) {
      std::printf("| channel SVM, %s: %s |\n", grouped ? "positions held out" : "random folds", err.c_str());
      continue;
    }
    Confusion c;
    for (size_t i = 0; i < sub.size(); ++i) c.add(sub[i].label != 0, pred[i] != 0);
    print_confusion_row(grouped ? "channel SVM, positions held out" : "channel SVM, random folds", c);
  }
  Confusion rule;
  for (const auto& s : samples) rule.add(s.label != 0, s.features[0] > 6.0F);
  print_confusion_row("channel rule (rx-fp > 6 dB)", rule);
  std::printf("(range-rate, consistency, filter and RAIM methods need sequences: n/a on a static table)\n");
}

int usage() {
  std::fprintf(stderr,
               "usage: uwbnav eval nlos [--protocol-seeds 11,12] [--drive-seeds 21,22] [--drive PRESET]\n"
               "         [--table FILE.csv] [--folds K] [--no-positioning] [--quick] [--hour]\n"
               "  --hour: also the one-hour drive (drive_1h) for long-run stability\n");
  return 2;
}

}  // namespace

Status score_method(const dataset::Recording& rec, const NlosMethod& method, const std::vector<size_t>& subset,
                    Confusion& confusion, std::vector<ErrorSample>* errors, std::string* error) {
  ReplayOptions ro;
  ro.params.emplace_back("gate.policy", static_cast<float>(method.policy));
  for (const auto& p : method.params) ro.params.push_back(p);
  ReplayResult rr;
  if (!ok(run_replay(rec, ro, rr, error))) return Status::kInvalidArgument;
  const std::map<RangeKey, size_t> idx = index_ranges(rec);
  std::vector<int8_t> decided(rec.uwb.size(), -1);
  for (const RangeReport& r : rr.ranges) {
    const auto it = idx.find(RangeKey{r.t_us, r.anchor_id, r.tag_id});
    if (it != idx.end()) decided[it->second] = r.nlos ? 1 : 0;
  }
  const std::vector<size_t> all = subset.empty() ? labelled(rec) : subset;
  for (size_t i : all) {
    if (rec.uwb[i].nlos_label < 0 || decided[i] < 0) continue;
    confusion.add(rec.uwb[i].nlos_label > 0, decided[i] > 0);
  }
  if (errors != nullptr && !rec.truth.empty()) *errors = compare_with_truth(rr.estimates, rec.truth);
  return Status::kOk;
}

int run_eval_nlos(int argc, char** argv) {
  std::vector<uint64_t> protocol_seeds = {11, 12};
  std::vector<uint64_t> drive_seeds = {21, 22, 23};
  std::string drive = "parking_nlos";
  std::string table = find_real_data_dir() + "/hanyang/hanyang_static_nlos_features.csv";
  int folds = 5;
  bool positioning = true;
  bool hour = false;
  size_t table_samples = 6000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--no-positioning") {
      positioning = false;
      continue;
    }
    if (a == "--hour") {
      hour = true;
      continue;
    }
    if (a == "--quick") {
      protocol_seeds = {11};
      drive_seeds = {21};
      table_samples = 2000;
      continue;
    }
    if (i + 1 >= argc) return usage();
    const std::string v = argv[++i];
    if (a == "--protocol-seeds") {
      protocol_seeds = parse_seeds(v);
    } else if (a == "--drive-seeds") {
      drive_seeds = parse_seeds(v);
    } else if (a == "--drive") {
      drive = v;
    } else if (a == "--table") {
      table = v;
    } else if (a == "--folds") {
      folds = std::max(2, std::atoi(v.c_str()));
    } else {
      return usage();
    }
  }
  std::printf("NLOS identification in the form of seed 000 Table 2: precision / recall / accuracy [%%],\n"
              "NLOS = positive class. Every method runs inside the Navigator (gate.policy) on held-out\n"
              "seeds; the committed SVMs were trained on seeds 101-103 (never evaluated here).\n");
  // (a) seed 000 protocol: 30 % stratified test split of each held-out recording.
  SetResult prot;
  std::string seeds_text;
  for (uint64_t seed : protocol_seeds) {
    dataset::Recording rec;
    std::string err;
    if (!ok(sim::simulate("seed000_protocol", seed, rec, &err))) {
      std::fprintf(stderr, "uwbnav eval nlos: %s\n", err.c_str());
      return 1;
    }
    std::fprintf(stderr, "(a) seed000_protocol seed %" PRIu64 "\n", seed);
    if (!evaluate_recording(rec, test_split(rec, 0.3, seed + 1000U), false, prot)) return 1;
    seeds_text += (seeds_text.empty() ? "" : ",") + std::to_string(seed);
  }
  print_set(("(a) seed000_protocol (seed 000 §2.1: LOS drive, half of the ranges +U[1,2] m), seeds " + seeds_text +
             ", 30 % test split")
                .c_str(),
            prot, false);
  // (b) geometric NLOS drives, all labelled ranges, positioning too.
  SetResult drv;
  seeds_text.clear();
  for (uint64_t seed : drive_seeds) {
    dataset::Recording rec;
    std::string err;
    if (!ok(sim::simulate(drive, seed, rec, &err))) {
      std::fprintf(stderr, "uwbnav eval nlos: %s\n", err.c_str());
      return 1;
    }
    std::fprintf(stderr, "(b) %s seed %" PRIu64 "\n", drive.c_str(), seed);
    if (!evaluate_recording(rec, {}, positioning, drv)) return 1;
    seeds_text += (seeds_text.empty() ? "" : ",") + std::to_string(seed);
  }
  print_set(("(b) " + drive + " (obstacle and body NLOS, gross outliers), seeds " + seeds_text + ", all ranges").c_str(),
            drv, positioning);
  // (c) real channel feature table.
  evaluate_table(table, folds, 7, table_samples);
  // Long drive: no divergence over an hour (drive_1h preset).
  if (hour) {
    SetResult longrun;
    dataset::Recording rec;
    std::string err;
    if (!ok(sim::simulate("drive_1h", 31, rec, &err))) {
      std::fprintf(stderr, "uwbnav eval nlos: %s\n", err.c_str());
      return 1;
    }
    std::fprintf(stderr, "drive_1h seed 31\n");
    if (!evaluate_recording(rec, {}, true, longrun)) return 1;
    print_set("(d) drive_1h (one hour of parking_nlos loops), seed 31, all ranges", longrun, true);
  }
  return 0;
}

}  // namespace uwbnav::eval
