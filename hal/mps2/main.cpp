// Firmware image entry for the MPS2-AN386 board under qemu-system-arm: replays
// the recording in flash through App::tick() on the 10 ms grid exactly as the
// host lockstep replay does (tools/eval/replay.cpp), measures each cycle with
// the SysTick counter, prints a digest over semihosting ("key a=b ..." lines,
// read by check_replay.py and footprint_report.py) and exits 0 (1: init
// failed, 2: stack fully used; 3 and 4 from startup.cpp). The
// profile build (UWBNAV_MPS2_PROFILE) prints a sampled PC histogram instead of
// the per-cycle cost.
#include <cstdint>

#include "estimator/navigator.hpp"
#include "estimator/nlos/gating_layer.hpp"
#include "firmware/app.hpp"
#include "firmware/console/console.hpp"
#include "hal/mps2/board.hpp"
#include "hal/mps2/flash_recording.hpp"
#include "hal/mps2/text_out.hpp"
#ifdef UWBNAV_MPS2_PROFILE
#include "hal/mps2/profile.hpp"
#endif

namespace uwbnav::mps2 {
namespace {

constexpr uint32_t kCostBins = 6;                 // ranges per cycle 0..4, 5+
constexpr uint64_t kTrajectoryPeriodUs = 1000000;  // digest trajectory sample period [us]
constexpr uint32_t kCalibrationInstructions = 2000000;

// Per-cycle cost, binned by the number of ranges the cycle handled.
struct CostBin {
  uint32_t cycles = 0;
  uint64_t ticks_sum = 0;
  uint32_t ticks_max = 0;
};

// What the firmware computed, condensed for the digest.
class DigestObserver final : public AppObserver {
 public:
  explicit DigestObserver(TextOut& out) : out_(out) {}

  void on_range(const RangeReport& r) override {
    ++ranges_reported_;
    ++ranges_this_cycle_;
    if (r.used) ++ranges_used_;
    if (r.nlos) ++ranges_nlos_;
  }

  void on_output(const NavOutput& o) override {
    ++outputs_;
    const auto s = static_cast<uint32_t>(o.status);
    if (s < 4) ++status_cycles_[s];
    last_ = o;
    if (o.t_us % kTrajectoryPeriodUs == 0) trajectory_due_ = true;
  }

  // Prints the 1 Hz trajectory line of the last output, outside the measured tick.
  void print_trajectory() {
    if (!trajectory_due_) return;
    trajectory_due_ = false;
    out_.str("traj t_us=").u64(last_.t_us).str(" status=").u64(static_cast<uint32_t>(last_.status));
    out_.str(" pos_m=").fixed(last_.pos_nav_m.x, 4).str(",").fixed(last_.pos_nav_m.y, 4);
    out_.str(",").fixed(last_.pos_nav_m.z, 4).endl();
  }

  uint32_t take_cycle_ranges() {
    const uint32_t n = ranges_this_cycle_;
    ranges_this_cycle_ = 0;
    return n;
  }

  uint32_t ranges_reported_ = 0;
  uint32_t ranges_used_ = 0;
  uint32_t ranges_nlos_ = 0;
  uint32_t outputs_ = 0;
  uint32_t status_cycles_[4] = {};
  NavOutput last_;

 private:
  TextOut& out_;
  uint32_t ranges_this_cycle_ = 0;
  bool trajectory_due_ = false;
};

TextOut g_out;
SiteConfig g_site;
FlashImuSource g_imu(kFlashRecording);
FlashUwbSource g_uwb(kFlashRecording);
RingCanBus g_can;
NullSerialPort g_serial;
LockstepClock g_clock;
NullParamStore g_params;
hal::Board g_board{g_imu, g_uwb, g_can, g_serial, g_clock, g_params, g_site};
App g_app(g_board);
DigestObserver g_observer(g_out);
CostBin g_cost[kCostBins];

uint64_t first_sensor_time_us(const FlashRecording& rec) {
  uint64_t t = UINT64_MAX;
  if (rec.num_imu > 0) t = rec.t_base_us + rec.imu[0].dt_us;
  if (rec.num_uwb > 0 && rec.t_base_us + rec.uwb[0].dt_us < t) t = rec.t_base_us + rec.uwb[0].dt_us;
  return t == UINT64_MAX ? 0 : t;
}

// ticks * instructions / calibration ticks, rounded (instructions under -icount).
[[maybe_unused]] uint64_t to_instructions(uint64_t ticks, uint32_t calibration_ticks) {
  if (calibration_ticks == 0) return 0;
  return (ticks * kCalibrationInstructions + calibration_ticks / 2) / calibration_ticks;
}

void print_vec(const char* key, const Vec3f& v) {
  g_out.str(key).fixed(v.x, 6).str(",").fixed(v.y, 6).str(",").fixed(v.z, 6);
  g_out.str(" bits=").bits(v.x).str(",").bits(v.y).str(",").bits(v.z).endl();
}

// Per-cycle cost table of the digest (instructions under -icount shift=0).
[[maybe_unused]] void print_cost(uint32_t calibration_ticks, uint64_t cycles) {
  g_out.str("cost calibration_instructions=").u64(kCalibrationInstructions);
  g_out.str(" calibration_ticks=").u64(calibration_ticks).endl();
  uint64_t total_ticks = 0;
  uint32_t max_ticks = 0;
  for (uint32_t b = 0; b < kCostBins; ++b) {
    const CostBin& bin = g_cost[b];
    total_ticks += bin.ticks_sum;
    if (bin.ticks_max > max_ticks) max_ticks = bin.ticks_max;
    if (bin.cycles == 0) continue;
    g_out.str("cost ranges=").u64(b).str(b + 1 == kCostBins ? "+" : "").str(" cycles=").u64(bin.cycles);
    g_out.str(" mean_instructions=").u64(to_instructions(bin.ticks_sum, calibration_ticks) / bin.cycles);
    g_out.str(" max_instructions=").u64(to_instructions(bin.ticks_max, calibration_ticks)).endl();
  }
  g_out.str("cost all cycles=").u64(cycles);
  g_out.str(" mean_instructions=").u64(cycles ? to_instructions(total_ticks, calibration_ticks) / cycles : 0);
  g_out.str(" max_instructions=").u64(to_instructions(max_ticks, calibration_ticks)).endl();
}

int run() {
  CycleCounter::start();
  const uint32_t calibration_ticks = calibrate_ticks(kCalibrationInstructions);
#ifdef UWBNAV_MPS2_PROFILE
  profile_start();
#endif

  g_out.str("uwbnav-mps2 digest v1").endl();
  g_out.str("recording name=").str(kFlashRecording.name).str(" imu=").u64(kFlashRecording.num_imu);
  g_out.str(" uwb=").u64(kFlashRecording.num_uwb).endl();
  if (!ok(load_site(kFlashRecording, g_site))) {
    g_out.str("error: site table of the recording rejected").endl();
    return 1;
  }
  const Status init = g_app.init();
  if (!ok(init)) {
    g_out.str("error: App::init failed: ").str(status_name(init)).endl();
    return 1;
  }
  g_app.set_observer(&g_observer);

  // Loop time on the 10 ms grid from the cycle holding the first sample (as tools/eval/replay.cpp).
  const uint64_t t0 = first_sensor_time_us(kFlashRecording);
  uint64_t t = (t0 / kCyclePeriodUs + 1) * kCyclePeriodUs;
  uint64_t cycles = 0;
  uint64_t can_frames = 0;
  for (;;) {
    g_clock.sleep_until_us(t);
    const uint32_t begin = CycleCounter::now();
    g_app.tick(t);
    const uint32_t end = CycleCounter::now();
    const uint32_t ticks = CycleCounter::elapsed(begin, end);
    const uint32_t ranges = g_observer.take_cycle_ranges();
    CostBin& bin = g_cost[ranges < kCostBins ? ranges : kCostBins - 1];
    ++bin.cycles;
    bin.ticks_sum += ticks;
    if (ticks > bin.ticks_max) bin.ticks_max = ticks;
    ++cycles;
    g_observer.print_trajectory();
    hal::CanFrame f;
    while (ok(g_can.pop_sent(f))) ++can_frames;
    if (g_imu.finished() && g_uwb.finished()) break;
    t += kCyclePeriodUs;
  }

#ifdef UWBNAV_MPS2_PROFILE
  profile_report(g_out);
#endif
  const AppStats& st = g_app.stats();
  const NavDiagnostics& diag = g_app.navigator().diagnostics();
  const NavOutput& last = g_observer.last_;
  g_out.str("loop cycles=").u64(cycles).str(" outputs=").u64(g_observer.outputs_).endl();
  g_out.str("imu received=").u64(st.imu.received).str(" accepted=").u64(st.imu.accepted);
  g_out.str(" rejected=").u64(st.imu.rejected_total()).endl();
  g_out.str("uwb received=").u64(st.uwb.received).str(" accepted=").u64(st.uwb.accepted);
  g_out.str(" rejected=").u64(st.uwb.rejected_total()).endl();
  g_out.str("ranges reported=").u64(g_observer.ranges_reported_).str(" used=").u64(g_observer.ranges_used_);
  g_out.str(" nlos=").u64(g_observer.ranges_nlos_).endl();
  g_out.str("navigator imu_samples=").u64(diag.imu_samples).str(" ranges_used=").u64(diag.ranges_used);
  g_out.str(" ranges_rejected=").u64(diag.ranges_rejected).str(" resets=").u64(diag.resets);
  g_out.str(" reinits=").u64(diag.reinits).endl();
  g_out.str("status_cycles initialising=").u64(g_observer.status_cycles_[0]);
  g_out.str(" valid=").u64(g_observer.status_cycles_[1]).str(" degraded=").u64(g_observer.status_cycles_[2]);
  g_out.str(" invalid=").u64(g_observer.status_cycles_[3]).endl();
  g_out.str("can frames=").u64(can_frames).str(" dropped=").u64(g_can.counters().tx_dropped).endl();
  g_out.str("final t_us=").u64(last.t_us).str(" status=").u64(static_cast<uint32_t>(last.status));
  g_out.str(" (").str(nav_status_name(last.status)).str(")").endl();
  print_vec("final pos_m=", last.pos_nav_m);
  print_vec("final vel_mps=", last.vel_nav_mps);
  print_vec("final sigma_m=", last.pos_sigma_m);

#ifdef UWBNAV_MPS2_PROFILE
  // SysTick ran at the sampling period: per-cycle costs are not measured in this build.
  g_out.str("cost calibration_instructions=").u64(kCalibrationInstructions);
  g_out.str(" calibration_ticks=").u64(calibration_ticks).endl();
#else
  print_cost(calibration_ticks, cycles);
#endif
  const uint32_t stack_used = stack_used_bytes();
  g_out.str("memory sizeof_app=").u64(sizeof(App)).str(" sizeof_navigator=").u64(sizeof(Navigator));
  g_out.str(" sizeof_gating_layer=").u64(sizeof(GatingLayer)).str(" sizeof_console=").u64(sizeof(Console)).endl();
  g_out.str("stack used_bytes=").u64(stack_used).str(" reserved_bytes=").u64(stack_size_bytes()).endl();
  if (stack_used >= stack_size_bytes()) {
    g_out.str("error: the whole reserved stack was used (paint at its bottom gone)").endl();
    return 2;
  }
  g_out.str("end ok").endl();
  return 0;
}

}  // namespace
}  // namespace uwbnav::mps2

int main() { return uwbnav::mps2::run(); }
