// Result table of a replay (see summary.hpp).
#include "tools/eval/summary.hpp"

#include <cstdint>
#include <utility>

namespace uwbnav::eval {

namespace {

ErrorSample error_of(const dataset::EstimateRow& e, const double truth_nav_m[3]) {
  ErrorSample s;
  s.t_us = e.t_us;
  s.status = e.status;
  for (int k = 0; k < 3; ++k) {
    s.err_nav_m[k] = e.pos_nav_m[k] - truth_nav_m[k];
    s.sigma_nav_m[k] = e.pos_sigma_m[k];
  }
  return s;
}

}  // namespace

SummaryBuilder::SummaryBuilder(const SiteConfig& site, std::string name, dataset::RowFeed<dataset::UwbRow>& uwb,
                               dataset::RowFeed<dataset::TruthRow>* truth)
    : site_(site),
      name_(std::move(name)),
      uwb_(uwb),
      has_truth_(truth != nullptr && truth->peek() != nullptr),
      truth_(truth),
      ls_(site, LsMethod::kLinear, [this](const dataset::EstimateRow& fix) { on_ls_fix(fix); }) {}

void SummaryBuilder::take_ranges_up_to(uint64_t t_us) {
  dataset::UwbRow row;
  while (uwb_.peek() != nullptr && uwb_.peek()->range.t_us <= t_us && uwb_.next(row)) {
    nlos_labelled_ += row.nlos_label == 1 ? 1 : 0;
    if (has_truth_) ls_.add(row.range);
  }
}

// LS epochs reach here before any filter epoch of a later time, so the truth
// cursor sees non-decreasing times.
void SummaryBuilder::on_ls_fix(const dataset::EstimateRow& fix) {
  const dataset::TruthRow* a = nullptr;
  const dataset::TruthRow* b = nullptr;
  if (!truth_.bracket(fix.t_us, a, b)) return;
  double p[3];
  const dataset::TruthRow tb = tag_truth_row(site_, *b);
  if (a == nullptr) {
    for (int k = 0; k < 3; ++k) p[k] = tb.pos_nav_m[k];
  } else {
    interpolate(tag_truth_row(site_, *a), tb, fix.t_us, p);
  }
  ls_acc_.add(error_of(fix, p));
}

void SummaryBuilder::on_estimate(const dataset::EstimateRow& e) {
  take_ranges_up_to(e.t_us);
  if (!has_truth_) return;
  ls_.advance_to(e.t_us);
  double p[3];
  if (!truth_.position(e.t_us, p)) return;
  ++epochs_in_truth_;
  if (e.status != 1 && e.status != 2) return;  // valid or degraded only
  const ErrorSample err = error_of(e, p);
  filter_.add(err);
  // The same epochs split by the mode that published them (availability: share of all epochs).
  if (e.mode == static_cast<int>(NavMode::kNone)) return;
  (e.mode == static_cast<int>(NavMode::kInertial) ? inertial_ : fallback_).add(err);
}

RunSummary SummaryBuilder::finish(const ReplayResult& result) {
  take_ranges_up_to(UINT64_MAX);
  if (has_truth_) ls_.finish();
  RunSummary s;
  s.name = name_;
  s.has_truth = has_truth_;
  s.ranges_used = result.ranges_used;
  s.ranges_rejected = result.ranges_rejected;
  s.ranges_nlos_labelled = nlos_labelled_;
  s.input = result.stats;
  s.imu_rejected = result.stats.imu.rejected_total();
  s.uwb_rejected = result.stats.uwb.rejected_total();
  s.cycles = result.cycles;
  s.wall_s = result.wall_s;
  s.resets = result.diag.resets;
  s.reinits = result.diag.reinits;
  if (has_truth_) {
    s.filter = filter_.stats(epochs_in_truth_);
    s.inertial = inertial_.stats(epochs_in_truth_);
    s.fallback = fallback_.stats(epochs_in_truth_);
    s.ls_uwb = ls_acc_.stats(epochs_in_truth_);
  }
  return s;
}

RunSummary summarise(const dataset::Recording& rec, const ReplayResult& result) {
  dataset::VectorFeed<dataset::UwbRow> uwb(rec.uwb);
  dataset::VectorFeed<dataset::TruthRow> truth(rec.truth);
  SummaryBuilder builder(rec.site, rec.name(), uwb, &truth);
  for (const auto& e : result.estimates) builder.on_estimate(e);
  return builder.finish(result);
}

void print_summary(std::FILE* f, const RunSummary& s) {
  std::fprintf(f, "\nuwbnav result: %s\n\n", s.name.c_str());
  if (s.has_truth) {
    std::fprintf(f, "| method | epochs | availability | RMSE h [m] | MAX h [m] | STD h [m] | in 2-sigma x/y |\n");
    std::fprintf(f, "|---|---:|---:|---:|---:|---:|---:|\n");
    auto row = [&](const char* name, const AccuracyStats& a, bool sigma) {
      const double avail = a.epochs_total ? 100.0 * static_cast<double>(a.epochs) / static_cast<double>(a.epochs_total) : 0.0;
      std::fprintf(f, "| %s | %zu | %.1f %% | %.3f | %.3f | %.3f |", name, a.epochs, avail, a.rmse_h_m, a.max_h_m, a.std_h_m);
      if (sigma) {
        std::fprintf(f, " %.1f %% / %.1f %% |\n", 100.0 * a.inside_2sigma_x, 100.0 * a.inside_2sigma_y);
      } else {
        std::fprintf(f, " - |\n");
      }
    };
    row("uwbnav EKF (default gating)", s.filter, true);
    if (s.inertial.epochs > 0) row("- of which IMU filter", s.inertial, true);
    if (s.fallback.epochs > 0) row("- of which ranges-only fallback (start, alignment, recovery)", s.fallback, true);
    row("LS-UWB baseline (tag)", s.ls_uwb, false);
    std::fprintf(f, "\n");
  } else {
    std::fprintf(f, "(no truth in this recording: accuracy not computed)\n\n");
  }
  std::fprintf(f, "ranges used %llu, rejected by gating %llu (labelled NLOS in the recording: %llu)\n",
               static_cast<unsigned long long>(s.ranges_used), static_cast<unsigned long long>(s.ranges_rejected),
               static_cast<unsigned long long>(s.ranges_nlos_labelled));
  std::fprintf(f, "input frames rejected by validation: IMU %llu, UWB %llu; filter resets %u, re-inits %u\n",
               static_cast<unsigned long long>(s.imu_rejected), static_cast<unsigned long long>(s.uwb_rejected),
               s.resets, s.reinits);
  for (const auto* src : {&s.input.imu, &s.input.uwb}) {
    if (src->rejected_total() == 0) continue;
    std::fprintf(f, "  %s rejects:", src == &s.input.imu ? "IMU" : "UWB");
    for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
      if (src->rejected[r] > 0) std::fprintf(f, " %s %u", reject_reason_name(static_cast<RejectReason>(r)), src->rejected[r]);
    }
    std::fprintf(f, "\n");
  }
  std::fprintf(f, "firmware cycles %llu in %.3f s wall (%.0f cycles/s)\n", static_cast<unsigned long long>(s.cycles),
               s.wall_s, s.wall_s > 0 ? static_cast<double>(s.cycles) / s.wall_s : 0.0);
}

}  // namespace uwbnav::eval
