// Estimator benchmarks: EKF predict step, one gated range update and a full
// 100 Hz cycle (IMU sample + 4 ranges + output) on a warmed-up filter driven by
// the simulated parking-lot drive (target: full cycle < 5 us median).
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "estimator/ekf_core.hpp"
#include "estimator/navigator.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

// One 10 ms cycle: one IMU sample and 4 ranges (one per anchor) computed from
// the truth of that cycle, stamped 8, 6, 4, 2 ms before the cycle end.
struct Cycle {
  uint64_t t_us = 0;
  ImuSample imu;
  UwbRange ranges[4];
};

struct Fixture {
  std::unique_ptr<Navigator> warm;  // filter running (state after the warm-up)
  std::vector<Cycle> cycles;        // input after the warm-up
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture out;
    dataset::Recording rec;
    std::string err;
    if (sim::simulate("parking_los", 42, rec, &err) != Status::kOk || rec.site.num_anchors < 4 ||
        rec.truth.size() != rec.imu.size()) {
      return out;
    }
    out.warm = std::make_unique<Navigator>();
    if (out.warm->configure(rec.site, Params{}) != Status::kOk) return out;
    constexpr uint64_t kWarmUs = 30000000;  // past initialisation, vehicle moving
    size_t j = 0;
    for (size_t i = 0; i < rec.imu.size(); ++i) {
      const ImuSample& s = rec.imu[i];
      if (s.t_us <= kWarmUs) {
        (void)out.warm->on_imu(s);
        while (j < rec.uwb.size() && rec.uwb[j].range.t_us <= s.t_us) (void)out.warm->on_range(rec.uwb[j++].range);
        continue;
      }
      Cycle c;
      c.t_us = s.t_us;
      c.imu = s;
      const dataset::TruthRow& tr = rec.truth[i];
      const Tag& tag = rec.site.tags[0];
      // Tag antenna from the truth pose (Hamilton body->nav rotation of the lever arm).
      const double w = tr.q_nav_body[0], x = tr.q_nav_body[1], y = tr.q_nav_body[2], z = tr.q_nav_body[3];
      const double l[3] = {static_cast<double>(tag.lever_body_m.x), static_cast<double>(tag.lever_body_m.y),
                           static_cast<double>(tag.lever_body_m.z)};
      const double rot[3][3] = {{w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)},
                                {2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)},
                                {2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z}};
      double p_tag[3];
      for (int r = 0; r < 3; ++r) p_tag[r] = tr.pos_nav_m[r] + rot[r][0] * l[0] + rot[r][1] * l[1] + rot[r][2] * l[2];
      for (int a = 0; a < 4; ++a) {
        const Anchor& an = rec.site.anchors[a];
        const double dx = p_tag[0] - static_cast<double>(an.pos_nav_m.x);
        const double dy = p_tag[1] - static_cast<double>(an.pos_nav_m.y);
        const double dz = p_tag[2] - static_cast<double>(an.pos_nav_m.z);
        c.ranges[a].t_us = s.t_us - 8000 + static_cast<uint64_t>(a) * 2000;
        c.ranges[a].anchor_id = an.id;
        c.ranges[a].tag_id = tag.id;
        c.ranges[a].range_m = static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz));
      }
      out.cycles.push_back(c);
    }
    return out;
  }();
  return f;
}

void BM_EkfPredict(benchmark::State& state) {
  EkfCore ekf;
  ekf.init(NominalState{}, ErrVec::Constant(Real(0.1)));
  const Vec3 f(Real(0.3), Real(-0.1), Real(9.8));
  const Vec3 w(Real(0.01), Real(0.02), Real(0.3));
  for (auto _ : state) {
    ekf.predict_imu(f, w, Real(0.01), Real(9.80665), ImuNoise{});
    benchmark::DoNotOptimize(ekf.cov().data());
    if (!ekf.sanitise()) ekf.init(NominalState{}, ErrVec::Constant(Real(0.1)));
  }
}
BENCHMARK(BM_EkfPredict);

void BM_NavigatorRangeUpdate(benchmark::State& state) {
  const Fixture& f = fixture();
  if (!f.warm || f.cycles.empty()) {
    state.SkipWithError("simulator unavailable");
    return;
  }
  auto nav = std::make_unique<Navigator>(*f.warm);
  // The same range again and again (same time: no prediction in between).
  const UwbRange r = f.cycles.front().ranges[0];
  for (auto _ : state) {
    const RangeReport rep = nav->on_range(r);
    benchmark::DoNotOptimize(rep.innovation_m);
  }
}
BENCHMARK(BM_NavigatorRangeUpdate);

// A full 100 Hz cycle: the cycle's IMU sample(s), 4 ranges, the output.
void BM_NavigatorCycle4Ranges(benchmark::State& state) {
  const Fixture& f = fixture();
  if (!f.warm || f.cycles.empty()) {
    state.SkipWithError("simulator unavailable");
    return;
  }
  auto nav = std::make_unique<Navigator>(*f.warm);
  size_t k = 0;
  for (auto _ : state) {
    if (k == f.cycles.size()) {
      state.PauseTiming();
      *nav = *f.warm;
      k = 0;
      state.ResumeTiming();
    }
    const Cycle& c = f.cycles[k++];
    (void)nav->on_imu(c.imu);
    for (const UwbRange& r : c.ranges) {
      const RangeReport rep = nav->on_range(r);
      benchmark::DoNotOptimize(rep.innovation_m);
    }
    const NavOutput o = nav->output(c.t_us);
    benchmark::DoNotOptimize(o.pos_nav_m.x);
  }
}
BENCHMARK(BM_NavigatorCycle4Ranges);

}  // namespace
}  // namespace uwbnav
