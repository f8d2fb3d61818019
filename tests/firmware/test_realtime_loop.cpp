// RealtimeLoop tests on a fake clock whose sleep advances time (with a chosen
// wake-up latency) and whose tick work time the test controls: deadlines on
// the 10 ms grid, no drift, overruns counted with missed deadlines skipped,
// start jitter and work time recorded, stop flag honoured.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "firmware/app.hpp"
#include "firmware/realtime_loop.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/idle_sources.hpp"
#include "hal/host/mem_can_bus.hpp"

namespace uwbnav {
namespace {

// Sleep jumps to the deadline plus a wake-up latency; work is added by the observer.
class FakeClock final : public hal::Clock {
 public:
  explicit FakeClock(uint64_t start_us) : t_us_(start_us) {}
  uint64_t now_us() override { return t_us_; }
  void sleep_until_us(uint64_t deadline_us) override {
    requested.push_back(deadline_us);
    if (deadline_us > t_us_) t_us_ = deadline_us + wake_latency_us;
  }
  void advance(uint64_t dt_us) { t_us_ += dt_us; }

  uint64_t wake_latency_us = 0;
  std::vector<uint64_t> requested;  // every deadline the loop slept to

 private:
  uint64_t t_us_;
};

// Called inside App::tick: spends the scripted work time on the fake clock,
// records the tick time and can raise the stop flag.
class WorkScript final : public AppObserver {
 public:
  WorkScript(FakeClock& clock, volatile bool& stop) : clock_(clock), stop_(stop) {}
  void on_range(const RangeReport&) override {}
  void on_output(const NavOutput& out) override {
    tick_us.push_back(out.t_us);
    const size_t k = tick_us.size() - 1;
    clock_.advance(work_us ? work_us(k) : 0);
    if (stop_after != 0 && tick_us.size() >= stop_after) stop_ = true;
  }
  uint64_t (*work_us)(size_t cycle) = nullptr;
  size_t stop_after = 0;
  std::vector<uint64_t> tick_us;

 private:
  FakeClock& clock_;
  volatile bool& stop_;
};

SiteConfig square_site() {
  SiteConfig s;
  EXPECT_TRUE(ok(s.add_anchor(1, {0, 0, 2})));
  EXPECT_TRUE(ok(s.add_anchor(2, {20, 0, 2})));
  EXPECT_TRUE(ok(s.add_anchor(3, {20, 20, 2})));
  EXPECT_TRUE(ok(s.add_anchor(4, {0, 20, 2})));
  EXPECT_TRUE(ok(s.add_tag(0, {0, 0, 1})));
  return s;
}

struct Rig {
  explicit Rig(uint64_t start_us) : clock(start_us), board{imu, uwb, can, serial, clock, store, site} {
    app = std::make_unique<App>(board);
    EXPECT_TRUE(ok(app->init()));
    app->set_observer(&script);
  }
  hal::IdleImuSource imu;
  hal::IdleUwbSource uwb;
  hal::MemCanBus can;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  SiteConfig site = square_site();
  FakeClock clock;
  hal::Board board;
  std::unique_ptr<App> app;
  volatile bool stop = false;
  WorkScript script{clock, stop};
};

TEST(RealtimeLoop, DeadlinesAreOnThe10msGridStartingAtTheNextMultiple) {
  Rig rig(12345);
  rig.script.work_us = [](size_t) -> uint64_t { return 2000; };
  RealtimeLoop(*rig.app, rig.clock).run(rig.stop, 50);
  ASSERT_EQ(rig.script.tick_us.size(), 50U);
  for (size_t k = 0; k < 50; ++k) {
    EXPECT_EQ(rig.script.tick_us[k], 20000U + k * kCyclePeriodUs) << "cycle " << k;
    EXPECT_EQ(rig.clock.requested[k], rig.script.tick_us[k]);
  }
  EXPECT_EQ(rig.app->stats().loop.cycles, 50U);
  EXPECT_EQ(rig.app->stats().loop.overruns, 0U);
}

TEST(RealtimeLoop, NoDriftOverOneHundredThousandCyclesWithVaryingWorkAndLateWakeups) {
  Rig rig(7);
  rig.clock.wake_latency_us = 450;
  rig.script.work_us = [](size_t k) -> uint64_t { return 500 + (k * 7919) % 9000; };  // 0.5..9.5 ms
  RealtimeLoop(*rig.app, rig.clock).run(rig.stop, 100000);
  const auto& t = rig.script.tick_us;
  ASSERT_EQ(t.size(), 100000U);
  // Absolute deadlines: cycle k runs at first + k * period exactly, whatever the work and latency.
  EXPECT_EQ(t.back(), t.front() + 99999U * kCyclePeriodUs);
  EXPECT_EQ(rig.app->stats().loop.overruns, 0U);  // 450 us + 9.5 ms < 10 ms
  EXPECT_LT(rig.clock.now_us() - t.back(), kCyclePeriodUs);
}

TEST(RealtimeLoop, OverrunIsCountedOnceAndMissedDeadlinesAreSkippedNotBunched) {
  Rig rig(0);
  rig.script.work_us = [](size_t k) -> uint64_t { return k == 10 ? 25000 : 1000; };
  RealtimeLoop(*rig.app, rig.clock).run(rig.stop, 20);
  const auto& t = rig.script.tick_us;
  ASSERT_EQ(t.size(), 20U);
  // Cycle 10 starts at D and ends at D + 25 ms: D + 10 and D + 20 ms are skipped.
  EXPECT_EQ(t[11] - t[10], 3U * kCyclePeriodUs);
  for (size_t k = 1; k < t.size(); ++k) {
    EXPECT_EQ(t[k] % kCyclePeriodUs, 0U) << "tick off the grid at cycle " << k;
    if (k != 11) {
      EXPECT_EQ(t[k] - t[k - 1], kCyclePeriodUs) << "cycle " << k;
    }
  }
  const LoopStats& l = rig.app->stats().loop;
  EXPECT_EQ(l.overruns, 1U);
  EXPECT_EQ(l.cycles, 20U);
  EXPECT_EQ(l.cycle_max_us, 25000U);
  EXPECT_EQ(l.cycle_min_us, 1000U);
}

TEST(RealtimeLoop, LateWakeupPlusWorkBeyondTheNextDeadlineIsAnOverrun) {
  Rig rig(0);
  rig.clock.wake_latency_us = 3000;
  rig.script.work_us = [](size_t k) -> uint64_t { return k == 4 ? 8000 : 1000; };  // 3 + 8 ms > 10 ms
  RealtimeLoop(*rig.app, rig.clock).run(rig.stop, 10);
  EXPECT_EQ(rig.app->stats().loop.overruns, 1U);
  EXPECT_EQ(rig.script.tick_us[5] - rig.script.tick_us[4], 2U * kCyclePeriodUs);
}

TEST(RealtimeLoop, StartJitterAndWorkTimeAreRecorded) {
  Rig rig(0);
  rig.clock.wake_latency_us = 700;
  rig.script.work_us = [](size_t k) -> uint64_t { return k % 2 == 0 ? 1000 : 3000; };
  RealtimeLoop(*rig.app, rig.clock).run(rig.stop, 10);
  const LoopStats& l = rig.app->stats().loop;
  EXPECT_EQ(l.jitter_max_us, 700U);
  EXPECT_EQ(l.cycle_min_us, 1000U);
  EXPECT_EQ(l.cycle_max_us, 3000U);
  EXPECT_EQ(l.avg_us(), 2000U);
}

// The cycle-latency histogram (console `stats latency`, firmware exit summary,
// HIL report): deadline to end of work = wake-up latency + work, per bin.
TEST(RealtimeLoop, CycleLatencyHistogramCountsWakeupLatencyPlusWorkPerBin) {
  Rig rig(0);
  rig.clock.wake_latency_us = 700;
  rig.script.work_us = [](size_t k) -> uint64_t { return k < 6 ? 100 : (k < 9 ? 1500 : 12000); };
  RealtimeLoop(*rig.app, rig.clock).run(rig.stop, 10);
  const LoopStats& l = rig.app->stats().loop;
  EXPECT_EQ(l.latency_hist[latency_bin(800)], 6U);    // 700 + 100 us: <= 1000 bin
  EXPECT_EQ(l.latency_hist[latency_bin(2200)], 3U);   // 700 + 1500 us: <= 5000 bin
  EXPECT_EQ(l.latency_hist[latency_bin(12700)], 1U);  // 700 + 12000 us: <= 20000 bin, an overrun
  EXPECT_EQ(l.latency_max_us, 12700U);
  EXPECT_EQ(l.overruns, 1U);
  uint64_t total = 0;
  for (uint32_t n : l.latency_hist) total += n;
  EXPECT_EQ(total, l.cycles);
}

TEST(RealtimeLoop, LatencyBinsAreInclusiveUpperBoundsWithAnOpenLastBin) {
  EXPECT_EQ(latency_bin(0), 0U);
  EXPECT_EQ(latency_bin(50), 0U);
  EXPECT_EQ(latency_bin(51), 1U);
  EXPECT_EQ(latency_bin(10000), 7U);
  EXPECT_EQ(latency_bin(50000), kNumLatencyBins - 2);
  EXPECT_EQ(latency_bin(50001), kNumLatencyBins - 1);
  EXPECT_EQ(latency_bin(UINT32_MAX), kNumLatencyBins - 1);
}

TEST(RealtimeLoop, StopFlagRaisedInsideACycleEndsTheRunAfterThatCycle) {
  Rig rig(0);
  rig.script.stop_after = 7;
  RealtimeLoop(*rig.app, rig.clock).run(rig.stop);
  EXPECT_EQ(rig.script.tick_us.size(), 7U);
  EXPECT_EQ(rig.app->stats().loop.cycles, 7U);
}

TEST(RealtimeLoop, StepReturnsTheNextDeadlineOnTheGrid) {
  Rig rig(0);
  RealtimeLoop loop(*rig.app, rig.clock);
  EXPECT_EQ(loop.step(30000), 40000U);
  rig.script.work_us = [](size_t) -> uint64_t { return 15000; };
  EXPECT_EQ(loop.step(40000), 60000U);  // ends at 55 ms: 50 ms missed, next is 60 ms
}

}  // namespace
}  // namespace uwbnav
