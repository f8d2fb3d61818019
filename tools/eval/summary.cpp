// Result table of a replay (see summary.hpp).
#include "tools/eval/summary.hpp"

#include "tools/eval/baselines.hpp"

#include <vector>

namespace uwbnav::eval {

RunSummary summarise(const dataset::Recording& rec, const ReplayResult& result) {
  RunSummary s;
  s.name = rec.name();
  s.has_truth = !rec.truth.empty();
  s.ranges_used = result.ranges_used;
  s.ranges_rejected = result.ranges_rejected;
  s.input = result.stats;
  s.imu_rejected = result.stats.imu.rejected_total();
  s.uwb_rejected = result.stats.uwb.rejected_total();
  s.cycles = result.cycles;
  s.wall_s = result.wall_s;
  s.resets = result.diag.resets;
  s.reinits = result.diag.reinits;
  for (const auto& u : rec.uwb) s.ranges_nlos_labelled += u.nlos_label == 1 ? 1 : 0;
  if (s.has_truth) {
    size_t total = 0;
    for (const auto& e : result.estimates) {
      double p[3];
      if (truth_at(rec.truth, e.t_us, p)) ++total;
    }
    s.filter = accuracy(compare_with_truth(result.estimates, rec.truth), total);
    // The same epochs split by the mode that published them (availability: share of all epochs).
    std::vector<dataset::EstimateRow> by_mode[2];
    for (const auto& e : result.estimates) {
      if (e.mode == static_cast<int>(NavMode::kNone)) continue;
      by_mode[e.mode == static_cast<int>(NavMode::kInertial) ? 0 : 1].push_back(e);
    }
    s.inertial = accuracy(compare_with_truth(by_mode[0], rec.truth), total);
    s.fallback = accuracy(compare_with_truth(by_mode[1], rec.truth), total);
    const auto ls = ls_baseline(rec, LsMethod::kLinear);
    s.ls_uwb = accuracy(compare_with_truth(ls, tag_truth(rec)), total);
  }
  return s;
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
