// Cost of the NLOS modules per range (seed 000 Table 5 analog): SVM inference,
// consistency model, Dempster-Shafer, RAIM over an epoch, and the full
// GatingLayer::assess() of the paper's D-S policy and of the default policy.
#include <benchmark/benchmark.h>

#include <cmath>

#include "estimator/nlos/consistency.hpp"
#include "estimator/nlos/dempster_shafer.hpp"
#include "estimator/nlos/gating_layer.hpp"
#include "estimator/nlos/raim.hpp"
#include "estimator/nlos/svm_model.hpp"

namespace uwbnav {
namespace {

void BM_NlosSvmInference(benchmark::State& state) {
  float x[2] = {3.0F, 5.0F};
  for (auto _ : state) {
    x[0] = x[0] > 20.0F ? -20.0F : x[0] + 0.37F;
    const Result<float> p = svm_nlos_probability(kSvmModelRangeRateSpeed, x);
    benchmark::DoNotOptimize(p);
  }
  state.counters["support_vectors"] = kSvmModelRangeRateSpeed.num_sv;
}
BENCHMARK(BM_NlosSvmInference);

void BM_NlosConsistency(benchmark::State& state) {
  float dr = 0.0F;
  for (auto _ : state) {
    dr = dr > 3.0F ? -3.0F : dr + 0.011F;
    benchmark::DoNotOptimize(consistency_p_nlos(dr, 0.4F, 0.1F));
  }
}
BENCHMARK(BM_NlosConsistency);

void BM_NlosDempsterShafer(benchmark::State& state) {
  float p1 = 0.1F;
  for (auto _ : state) {
    p1 = p1 > 0.9F ? 0.1F : p1 + 0.001F;
    benchmark::DoNotOptimize(ds_combine(p1, 0.7F));
  }
}
BENCHMARK(BM_NlosDempsterShafer);

void BM_NlosRaimEpoch(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  LsRange r[kRaimMaxRanges];
  const Vec3f tag{20.0F, 15.0F, 1.7F};
  for (int i = 0; i < n; ++i) {
    const float ang = 6.2831853F * static_cast<float>(i) / static_cast<float>(n);
    r[i].anchor_pos_nav_m = Vec3f{30.0F + 30.0F * std::cos(ang), 20.0F + 20.0F * std::sin(ang), 0.2F};
    const float dx = tag.x - r[i].anchor_pos_nav_m.x;
    const float dy = tag.y - r[i].anchor_pos_nav_m.y;
    const float dz = tag.z - r[i].anchor_pos_nav_m.z;
    r[i].range_m = std::sqrt(dx * dx + dy * dy + dz * dz) + (i == 1 ? 1.5F : 0.0F);
    r[i].sigma_m = 0.1F;
  }
  LsOptions opt;
  opt.two_d = true;
  opt.known_z_m = tag.z;
  opt.has_initial_guess = true;
  opt.initial_guess_nav_m = Vec3f{19.0F, 16.0F, tag.z};
  RaimThresholds th;
  raim_compute_thresholds(1e-3F, 1e-3F, th);
  for (auto _ : state) {
    RaimResult res;
    benchmark::DoNotOptimize(raim_run(r, static_cast<size_t>(n), opt, th, res));
    benchmark::DoNotOptimize(res.num_excluded);
  }
}
BENCHMARK(BM_NlosRaimEpoch)->Arg(4)->Arg(8);

void assess_loop(benchmark::State& state, GatingPolicy policy) {
  SiteConfig site;
  ignore_status(site.add_anchor(1, Vec3f{0.0F, 0.0F, 0.2F}));
  ignore_status(site.add_anchor(2, Vec3f{60.0F, 0.0F, 0.2F}));
  ignore_status(site.add_anchor(3, Vec3f{60.0F, 40.0F, 0.2F}));
  ignore_status(site.add_anchor(4, Vec3f{0.0F, 40.0F, 0.2F}));
  Params params;
  ignore_status(params.set(ParamId::kGatePolicy, static_cast<float>(policy)));
  GatingLayer g;
  ignore_status(g.configure(site, params));
  RangeContext c;
  c.meas_var_m2 = 0.01F;
  c.innovation_var_m2 = 0.02F;
  c.speed_mps = 5.0F;
  c.dist_since_prev_m = 0.4F;
  c.filter_ready = true;
  c.tag_pos_nav_m = Vec3f{20.0F, 15.0F, 1.7F};
  uint64_t t = 0;
  int k = 0;
  for (auto _ : state) {
    c.anchor_index = k % 4;
    c.range.anchor_id = static_cast<uint16_t>(c.anchor_index + 1);
    c.range.t_us = t;
    c.innovation_m = (k % 7 == 0) ? 1.5F : 0.05F;
    c.range.range_m = 25.0F + c.innovation_m + 0.3F * static_cast<float>(k % 3);
    const GatingDecision d = g.assess(c);
    g.on_result(c, d, d.use);
    benchmark::DoNotOptimize(d);
    t += 20000;
    ++k;
  }
}

void BM_NlosAssessDempsterShafer(benchmark::State& state) { assess_loop(state, GatingPolicy::kDempsterShafer); }
BENCHMARK(BM_NlosAssessDempsterShafer);

void BM_NlosAssessRaim(benchmark::State& state) { assess_loop(state, GatingPolicy::kRaim); }
BENCHMARK(BM_NlosAssessRaim);

void BM_NlosAssessDefault(benchmark::State& state) { assess_loop(state, GatingPolicy::kDefault); }
BENCHMARK(BM_NlosAssessDefault);

}  // namespace
}  // namespace uwbnav
