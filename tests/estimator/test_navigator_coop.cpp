// Cooperative ranging of the Navigator (docs/ekf.md "Neighbour ranges"): ranges
// to neighbour vehicles' tags keep the solution through anchor outages with an
// honest claim, a car in the line of sight is gated, a range through a
// broadcasting car is refused as occluded, stale, dependent, vague and
// unknown neighbours are refused and counted, a neighbour's correlated error is
// not counted as fresh information with every range, and coop.enable = 0 leaves
// the estimator exactly as without neighbours. The neighbours and their ranges
// are made here from the simulated truth, so the tests do not depend on the
// simulator's multi-vehicle model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "tests/estimator/nav_harness.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav {
namespace {

dataset::Recording simulate_or_fail(const std::string& preset, uint64_t seed) {
  dataset::Recording rec;
  std::string err;
  EXPECT_EQ(sim::simulate(preset, seed, rec, &err), Status::kOk) << err;
  return rec;
}

// Parked neighbour vehicles around the 60 x 40 m parking lot (tags at roof height).
struct Parked {
  uint16_t id;
  double pos_nav_m[3];
};
const Parked kParked[] = {{0x8001, {30, -6, 1.7}}, {0x8002, {67, 20, 1.7}}, {0x8003, {30, 46, 1.7}},
                          {0x8004, {-7, 20, 1.7}}};

struct NeighbourPlan {
  double claim_sigma_h_m = 0.1;   // claimed horizontal 1-sigma; vertical twice that
  double range_sigma_m = 0.05;    // ranging noise
  bool constant_error = false;    // true: each broadcast carries one error drawn per vehicle (fully correlated)
  bool cooperative_8002 = false;  // vehicle 0x8002 says its own state is cooperative
  double bias_8001_m = 0.0;       // added to ranges to 0x8001 in [bias_from_s, bias_to_s): a car in the line of sight
  double bias_from_s = 0.0;
  double bias_to_s = 0.0;
  double broadcast_until_s = 1e9; // no broadcast after this
  double occluder_from_s = 0.0;   // in [occluder_from_s, occluder_to_s) vehicle 0x8005 broadcasts a position
  double occluder_to_s = 0.0;     // half-way between the ego's tag and 0x8001 (it does not range)
  uint32_t seed = 1;
};

// 10 Hz broadcasts (50 ms latency, zero velocity) and 10 Hz ranges from tag 0
// to every parked neighbour, merged into the recording in time order.
void add_neighbours(dataset::Recording& rec, const NeighbourPlan& plan) {
  std::mt19937 gen(plan.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  double fixed_err[4][3];
  for (auto& e : fixed_err) {
    for (double& v : e) v = unit(gen);
  }
  const Vec3 lever = to_vec3(rec.site.tags[0].lever_body_m);
  std::vector<dataset::UwbRow> extra;
  uint64_t next_us = 0;
  for (const dataset::TruthRow& tr : rec.truth) {
    if (tr.t_us < next_us || !tr.has_attitude) continue;
    next_us = (tr.t_us / 100000 + 1) * 100000;
    const double t_s = static_cast<double>(tr.t_us) * 1e-6;
    const Quat q(static_cast<Real>(tr.q_nav_body[0]), static_cast<Real>(tr.q_nav_body[1]),
                 static_cast<Real>(tr.q_nav_body[2]), static_cast<Real>(tr.q_nav_body[3]));
    const Vec3 lever_nav = quat_to_dcm(q) * lever;
    const double tag[3] = {tr.pos_nav_m[0] + static_cast<double>(lever_nav.x()),
                           tr.pos_nav_m[1] + static_cast<double>(lever_nav.y()),
                           tr.pos_nav_m[2] + static_cast<double>(lever_nav.z())};
    for (size_t k = 0; k < 4; ++k) {
      const Parked& p = kParked[k];
      if (t_s < plan.broadcast_until_s) {
        NeighbourState s;
        s.vehicle_id = p.id;
        s.t_us = tr.t_us;
        s.rx_t_us = tr.t_us + 50000;
        const double sh = plan.claim_sigma_h_m;
        double e[3];
        for (int a = 0; a < 3; ++a) {
          const double sd = a < 2 ? sh : 2.0 * sh;
          e[a] = sd * (plan.constant_error ? fixed_err[k][a] : unit(gen));
        }
        s.pos_nav_m = Vec3f{static_cast<float>(p.pos_nav_m[0] + e[0]), static_cast<float>(p.pos_nav_m[1] + e[1]),
                            static_cast<float>(p.pos_nav_m[2] + e[2])};
        const float vh = static_cast<float>(sh * sh);
        const float s_cov[6] = {vh, 0.0F, 0.0F, vh, 0.0F, 4.0F * vh};
        std::copy(s_cov, s_cov + 6, s.cov_pos_m2);
        s.vel_nav_mps = Vec3f{0.0F, 0.0F, 0.0F};
        s.cooperative = plan.cooperative_8002 && p.id == 0x8002;
        rec.neighbours.push_back(s);
      }
      if (k == 0 && t_s >= plan.occluder_from_s && t_s < plan.occluder_to_s) {
        NeighbourState o;
        o.vehicle_id = 0x8005;
        o.t_us = tr.t_us;
        o.rx_t_us = tr.t_us + 50000;
        o.pos_nav_m = Vec3f{static_cast<float>(0.5 * (tag[0] + p.pos_nav_m[0])),
                            static_cast<float>(0.5 * (tag[1] + p.pos_nav_m[1])),
                            static_cast<float>(0.5 * (tag[2] + p.pos_nav_m[2]))};
        const float o_cov[6] = {0.01F, 0.0F, 0.0F, 0.01F, 0.0F, 0.04F};
        std::copy(o_cov, o_cov + 6, o.cov_pos_m2);  // velocity not reported (NaN)
        rec.neighbours.push_back(o);
      }
      dataset::UwbRow row;
      row.range.t_us = tr.t_us + 10000 * (k + 1);
      row.range.anchor_id = p.id;
      row.range.tag_id = rec.site.tags[0].id;
      const double d = std::sqrt((tag[0] - p.pos_nav_m[0]) * (tag[0] - p.pos_nav_m[0]) +
                                 (tag[1] - p.pos_nav_m[1]) * (tag[1] - p.pos_nav_m[1]) +
                                 (tag[2] - p.pos_nav_m[2]) * (tag[2] - p.pos_nav_m[2]));
      const bool blocked = p.id == 0x8001 && t_s >= plan.bias_from_s && t_s < plan.bias_to_s;
      row.range.range_m = static_cast<float>(d + plan.range_sigma_m * unit(gen) + (blocked ? plan.bias_8001_m : 0.0));
      row.nlos_label = blocked ? 1 : 0;
      extra.push_back(row);
    }
  }
  std::stable_sort(rec.neighbours.begin(), rec.neighbours.end(),
                   [](const NeighbourState& a, const NeighbourState& b) { return a.rx_t_us < b.rx_t_us; });
  std::vector<dataset::UwbRow> merged;
  merged.reserve(rec.uwb.size() + extra.size());
  std::merge(rec.uwb.begin(), rec.uwb.end(), extra.begin(), extra.end(), std::back_inserter(merged),
             [](const dataset::UwbRow& a, const dataset::UwbRow& b) { return a.range.t_us < b.range.t_us; });
  rec.uwb = merged;
}

bool in_outage(double t_s) { return (t_s >= 41 && t_s < 45) || (t_s >= 81 && t_s < 90) || (t_s >= 121 && t_s < 135); }

struct OutageScore {
  size_t epochs = 0;
  size_t valid = 0;
  size_t inside = 0;  // per axis (x and y) inside 2 sigma
  double max_err_m = 0;
  double share_inside() const { return epochs ? static_cast<double>(inside) / (2.0 * static_cast<double>(epochs)) : 0; }
};

OutageScore score_outages(const test::RunScore& s) {
  OutageScore o;
  for (const test::ScoredOutput& so : s.outputs) {
    if (!in_outage(static_cast<double>(so.out.t_us) * 1e-6) || !so.has_truth) continue;
    ++o.epochs;
    o.valid += so.out.status == NavStatus::kValid ? 1U : 0U;
    o.max_err_m = std::max(o.max_err_m, std::hypot(so.err_nav_m[0], so.err_nav_m[1]));
    o.inside += (std::fabs(so.err_nav_m[0]) <= 2.0 * static_cast<double>(so.out.pos_sigma_m.x)) +
                (std::fabs(so.err_nav_m[1]) <= 2.0 * static_cast<double>(so.out.pos_sigma_m.y));
  }
  return o;
}

size_t count(const std::vector<RangeReport>& reports, uint16_t id, bool used, double from_s = 0, double to_s = 1e9) {
  size_t n = 0;
  for (const RangeReport& r : reports) {
    const double t = static_cast<double>(r.t_us) * 1e-6;
    if (r.anchor_id == id && r.used == used && t >= from_s && t < to_s) ++n;
  }
  return n;
}

TEST(NavigatorCoop, NeighbourRangesKeepTheSolutionValidAndHonestThroughAnchorOutages) {
  // GIVEN parking_outages (anchors silent [40,45), [80,90), [120,135)) and four
  // parked neighbours with 0.1 m claims that keep ranging
  dataset::Recording rec = simulate_or_fail("parking_outages", 14);
  const OutageScore alone = score_outages(test::replay(rec, Params{}));
  add_neighbours(rec, NeighbourPlan{});
  std::vector<RangeReport> reports;
  const test::RunScore s = test::replay(rec, Params{}, 0, UINT64_MAX, &reports);
  const OutageScore o = score_outages(s);
  size_t to_neighbours = 0;
  size_t fused = 0;
  for (const RangeReport& r : reports) {
    if (!is_vehicle_id(r.anchor_id)) continue;
    ++to_neighbours;
    fused += r.used ? 1U : 0U;
  }
  std::printf("neighbours through outages: fused %zu of %zu ranges, max error %.3f m (alone %.3f m), valid %zu of %zu "
              "epochs (alone %zu), inside 2 sigma %.3f\n",
              fused, to_neighbours, o.max_err_m, alone.max_err_m, o.valid, o.epochs, alone.valid, o.share_inside());
  // THEN nearly all of them are fused, the status stays valid where the
  // vehicle alone is degraded, the error stays at the neighbours' accuracy and
  // the claim holds
  EXPECT_TRUE(s.all_finite);
  EXPECT_GE(fused, to_neighbours * 90 / 100);
  EXPECT_EQ(s.diag.neighbour_used, fused);
  EXPECT_EQ(alone.valid, 0U);
  EXPECT_GE(o.valid, o.epochs * 99 / 100);
  EXPECT_LT(o.max_err_m, 0.4);
  EXPECT_GE(o.share_inside(), 0.9);
  EXPECT_EQ(s.diag.resets, 0U);
}

TEST(NavigatorCoop, CarInTheLineOfSightIsGatedNotFollowed) {
  // GIVEN ranges to 0x8001 lengthened by 1.5 m for 10 s while the anchors are silent
  dataset::Recording rec = simulate_or_fail("parking_outages", 21);
  NeighbourPlan plan;
  plan.bias_8001_m = 1.5;
  plan.bias_from_s = 121.0;
  plan.bias_to_s = 131.0;
  add_neighbours(rec, plan);
  std::vector<RangeReport> reports;
  const test::RunScore s = test::replay(rec, Params{}, 0, UINT64_MAX, &reports);
  const size_t gated = count(reports, 0x8001, false, 121.0, 131.0);
  const size_t fused = count(reports, 0x8001, true, 121.0, 131.0);
  const OutageScore o = score_outages(s);
  std::printf("car in the line of sight: %zu gated, %zu fused, max error in outages %.3f m\n", gated, fused, o.max_err_m);
  // THEN (nearly) every lengthened range is refused and the solution holds
  EXPECT_GE(gated, 95U);
  EXPECT_LE(fused, 5U);
  EXPECT_LT(o.max_err_m, 0.4);
  EXPECT_GE(s.diag.neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kGate)], gated);
}

TEST(NavigatorCoop, RangeThroughABroadcastingCarIsRefusedEvenWhenItsDetourPassesTheGate) {
  // GIVEN ranges to 0x8001 lengthened by 0.5 m (inside the 4-sigma gate) for
  // 10 s while the anchors are silent, and a car (0x8005) broadcasting a
  // position on that line of sight in the same 10 s
  dataset::Recording rec = simulate_or_fail("parking_outages", 21);
  NeighbourPlan plan;
  plan.bias_8001_m = 0.5;
  plan.bias_from_s = 121.0;
  plan.bias_to_s = 131.0;
  plan.occluder_from_s = 121.0;
  plan.occluder_to_s = 131.0;
  add_neighbours(rec, plan);
  std::vector<RangeReport> reports;
  const test::RunScore s = test::replay(rec, Params{}, 0, UINT64_MAX, &reports);
  Params no_test;
  ASSERT_EQ(no_test.set(ParamId::kCoopOccluderM, 0.0F), Status::kOk);
  std::vector<RangeReport> reports_off;
  const test::RunScore off = test::replay(rec, no_test, 0, UINT64_MAX, &reports_off);
  const size_t refused = count(reports, 0x8001, false, 121.2, 131.0);
  const size_t fused = count(reports, 0x8001, true, 121.2, 131.0);
  const size_t fused_off = count(reports_off, 0x8001, true, 121.2, 131.0);
  std::printf("car on the line of sight: %zu refused, %zu fused (%zu fused without the occlusion test); "
              "max error in outages %.3f m (%.3f m without)\n",
              refused, fused, fused_off, score_outages(s).max_err_m, score_outages(off).max_err_m);
  // THEN the lengthened ranges are refused as occluded, which the gate alone
  // does not do, and ranges to the other vehicles are not affected
  EXPECT_GE(refused, 90U);
  EXPECT_LE(fused, 2U);
  EXPECT_GE(fused_off, 50U);
  EXPECT_GE(s.diag.neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kOccluded)], refused);
  EXPECT_EQ(off.diag.neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kOccluded)], 0U);
  EXPECT_EQ(count(reports, 0x8001, false, 135.0), count(reports_off, 0x8001, false, 135.0));
  EXPECT_LE(count(reports, 0x8003, false, 121.2, 131.0), 2U);
}

TEST(NavigatorCoop, StaleDependentVagueAndUnknownNeighboursAreRefusedAndCounted) {
  // GIVEN broadcasts that stop at 100 s, 0x8002 whose state is itself cooperative,
  // and ranges to 0x8005 which never broadcasts
  dataset::Recording rec = simulate_or_fail("parking_los", 5);
  NeighbourPlan plan;
  plan.cooperative_8002 = true;
  plan.broadcast_until_s = 100.0;
  add_neighbours(rec, plan);
  for (dataset::UwbRow& row : rec.uwb) {
    if (row.range.anchor_id == 0x8004 && row.range.t_us % 200000 == 40000) row.range.anchor_id = 0x8005;
  }
  std::vector<RangeReport> reports;
  const test::RunScore s = test::replay(rec, Params{}, 0, UINT64_MAX, &reports);
  const NavDiagnostics& d = s.diag;
  const auto rejected = [&](NeighbourVerdict v) { return d.neighbour_rejected[static_cast<size_t>(v)]; };
  // THEN every range to the dependent vehicle is refused as such, ranges after
  // the broadcasts stopped (0.5 s of coop.max_age later) are stale, and the
  // silent vehicle is unknown; the counts add up
  EXPECT_EQ(count(reports, 0x8002, true), 0U);
  EXPECT_GE(rejected(NeighbourVerdict::kDependent), count(reports, 0x8002, false, 1.0, 100.0));
  EXPECT_GE(rejected(NeighbourVerdict::kStale), count(reports, 0x8001, false, 101.0) + count(reports, 0x8003, false, 101.0));
  EXPECT_EQ(count(reports, 0x8001, true, 101.0), 0U);
  EXPECT_GE(rejected(NeighbourVerdict::kUnknown), count(reports, 0x8005, false));  // and the first ranges before any broadcast arrived
  EXPECT_GT(rejected(NeighbourVerdict::kUnknown), 100U);
  uint32_t total = d.neighbour_used;
  for (uint32_t r : d.neighbour_rejected) total += r;
  EXPECT_EQ(total, d.neighbour_ranges);

  // AND a neighbour claiming 3 m (coop.max_sigma 1 m) is not ranged against
  dataset::Recording vague = simulate_or_fail("parking_los", 6);
  NeighbourPlan wide;
  wide.claim_sigma_h_m = 3.0;
  add_neighbours(vague, wide);
  const test::RunScore sv = test::replay(vague, Params{});
  EXPECT_EQ(sv.diag.neighbour_used, 0U);
  EXPECT_GT(sv.diag.neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kUncertain)], 1000U);
}

TEST(NavigatorCoop, CorrelatedNeighbourErrorIsNotCountedAsNewWithEveryRange) {
  // GIVEN neighbours whose broadcast error is one draw per vehicle (0.15 m
  // claimed, constant): ranges to them repeat the same error
  dataset::Recording rec = simulate_or_fail("parking_outages", 31);
  NeighbourPlan plan;
  plan.constant_error = true;
  plan.claim_sigma_h_m = 0.15;
  plan.seed = 4;
  add_neighbours(rec, plan);
  const OutageScore weighted = score_outages(test::replay(rec, Params{}));
  Params white;
  ASSERT_EQ(white.set(ParamId::kCoopCorrTime, 0.0F), Status::kOk);
  const OutageScore naive = score_outages(test::replay(rec, white));
  std::printf("constant neighbour errors: inside 2 sigma %.3f with coop.corr_time 10 s, %.3f with 0 (max error %.3f / %.3f m)\n",
              weighted.share_inside(), naive.share_inside(), weighted.max_err_m, naive.max_err_m);
  // THEN weighting each range by the correlation time keeps the claim honest;
  // treating each range's share of the neighbour error as white does not
  EXPECT_GE(weighted.share_inside(), 0.9);
  EXPECT_LT(naive.share_inside(), weighted.share_inside() - 0.1);
}

// Equal, or both NaN (no estimate yet).
bool same_float(float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

TEST(NavigatorCoop, DisabledLeavesTheSolutionBitIdenticalToNoNeighbours) {
  dataset::Recording rec = simulate_or_fail("parking_los", 8);
  const test::RunScore without = test::replay(rec, Params{});
  add_neighbours(rec, NeighbourPlan{});
  Params off;
  ASSERT_EQ(off.set(ParamId::kCoopEnable, 0.0F), Status::kOk);
  const test::RunScore s = test::replay(rec, off);
  ASSERT_EQ(s.outputs.size(), without.outputs.size());
  for (size_t k = 0; k < s.outputs.size(); ++k) {
    const NavOutput& a = s.outputs[k].out;
    const NavOutput& b = without.outputs[k].out;
    ASSERT_TRUE(same_float(a.pos_nav_m.x, b.pos_nav_m.x) && same_float(a.pos_nav_m.y, b.pos_nav_m.y) &&
                same_float(a.pos_sigma_m.x, b.pos_sigma_m.x) && a.status == b.status)
        << "epoch " << k;
  }
  EXPECT_EQ(s.diag.neighbour_used, 0U);
  EXPECT_EQ(s.diag.neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kDisabled)], s.diag.neighbour_ranges);
}

TEST(NavigatorCoop, FullTableEvictsTheVehicleHeardFromLeastRecentlyAndOlderStatesAreRefused) {
  Navigator nav;
  SiteConfig site;
  for (uint16_t i = 0; i < 4; ++i) {
    ASSERT_EQ(site.add_anchor(i, Vec3f{static_cast<float>(10 * (i & 1U)), static_cast<float>(10 * (i >> 1U)), 2.0F}),
              Status::kOk);
  }
  ASSERT_EQ(nav.configure(site, Params{}), Status::kOk);
  NeighbourState s;
  const float cov[6] = {0.01F, 0.0F, 0.0F, 0.01F, 0.0F, 0.04F};
  std::copy(cov, cov + 6, s.cov_pos_m2);
  for (uint16_t k = 0; k < kMaxNeighbours + 1; ++k) {
    s.vehicle_id = static_cast<uint16_t>(kFirstVehicleId + 1 + k);
    s.t_us = 1000000 + 1000U * k;
    s.rx_t_us = s.t_us + 20000;
    EXPECT_EQ(nav.on_neighbour_state(s), Status::kOk) << k;
  }
  EXPECT_EQ(nav.diagnostics().neighbour_states, kMaxNeighbours + 1);
  EXPECT_EQ(nav.diagnostics().neighbour_evictions, 1U);
  // The first vehicle (heard least recently) is gone: a range to it is unknown.
  UwbRange r;
  r.t_us = 1100000;
  r.anchor_id = static_cast<uint16_t>(kFirstVehicleId + 1);
  r.range_m = 5.0F;
  static_cast<void>(nav.on_range(r));
  EXPECT_EQ(nav.diagnostics().neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kUnknown)], 1U);
  // A vehicle still in the table: no filter yet (neighbour ranges never start one).
  r.anchor_id = static_cast<uint16_t>(kFirstVehicleId + 2);
  static_cast<void>(nav.on_range(r));
  EXPECT_EQ(nav.diagnostics().neighbour_rejected[static_cast<size_t>(NeighbourVerdict::kNoFilter)], 1U);
  // An older state of a known vehicle, an anchor id, a non-positive-definite covariance: refused.
  NeighbourState older = s;
  older.t_us -= 1;
  EXPECT_EQ(nav.on_neighbour_state(older), Status::kInvalidArgument);
  NeighbourState anchor = s;
  anchor.vehicle_id = 3;
  EXPECT_EQ(nav.on_neighbour_state(anchor), Status::kInvalidArgument);
  NeighbourState bad = s;
  bad.cov_pos_m2[1] = 0.02F;  // |rho_xy| > 1
  EXPECT_EQ(nav.on_neighbour_state(bad), Status::kInvalidArgument);
  EXPECT_EQ(nav.diagnostics().neighbour_states, kMaxNeighbours + 1);
}

}  // namespace
}  // namespace uwbnav
