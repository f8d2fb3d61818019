// The uwbnav application: one 10 ms cycle (`tick`) drains the IMU and UWB
// frames due, validates them, runs the estimator in sensor-time order, emits
// CAN and services the console. Static memory only; one instance per board.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/navigator.hpp"
#include "estimator/params.hpp"
#include "firmware/app_stats.hpp"
#include "firmware/can/publisher.hpp"
#include "firmware/can/sensor_decoder.hpp"
#include "firmware/console/console.hpp"
#include "firmware/input_validator.hpp"
#include "hal/hal.hpp"

namespace uwbnav {

constexpr uint32_t kCyclePeriodUs = 10000;  // 100 Hz loop
// Frames accepted per cycle; more wait in the HAL source for the next cycle.
// Boards with little RAM set smaller capacities at build time (hal/mps2:
// a 10 ms cycle sees ~3 IMU samples at 250 Hz and a few ranges).
#ifndef UWBNAV_MAX_IMU_PER_CYCLE
#define UWBNAV_MAX_IMU_PER_CYCLE 32
#endif
#ifndef UWBNAV_MAX_UWB_PER_CYCLE
#define UWBNAV_MAX_UWB_PER_CYCLE 32
#endif
constexpr size_t kMaxImuPerCycle = UWBNAV_MAX_IMU_PER_CYCLE;
constexpr size_t kMaxUwbPerCycle = UWBNAV_MAX_UWB_PER_CYCLE;
static_assert(kMaxImuPerCycle >= 1 && kMaxUwbPerCycle >= 1, "a cycle must accept at least one frame of each");
constexpr size_t kMaxCanRxPerCycle = 64;    // HIL input frames read per cycle
constexpr size_t kMaxGnssPerCycle = 4;      // GNSS fixes drained per cycle (receivers send 1-20 Hz)
constexpr size_t kMaxNeighboursPerCycle = 8;  // neighbour states drained per cycle from the board source
#ifndef UWBNAV_MAX_CAN_PENDING
#define UWBNAV_MAX_CAN_PENDING 16
#endif
constexpr size_t kMaxCanPending = UWBNAV_MAX_CAN_PENDING;  // HIL samples held for the next cycle; beyond: validated now (future)

// Host-side tap on what the firmware computed (replay writers, tests, HIL).
// The firmware calls it synchronously; implementations must not block.
class AppObserver {
 public:
  virtual ~AppObserver() = default;
  virtual void on_range(const RangeReport& report) = 0;
  virtual void on_output(const NavOutput& output) = 0;
  // What the estimator did with a GNSS fix (boards with a receiver).
  virtual void on_gnss(const GnssReport& report) { static_cast<void>(report); }
};

class App {
 public:
  explicit App(hal::Board& board);

  // Loads parameters from the store (defaults when empty/corrupt), configures
  // the estimator with the board's site. Call once before the first tick.
  // kInvalidArgument (and no ticks run) when the site's range calibration is
  // unusable: offsets non-finite or beyond +-10 m, sigma outside (0, 1] m, or
  // offsets set on an uncalibrated (sigma NaN) site.
  [[nodiscard]] Status init();

  // One cycle at loop time now_us (the cycle's deadline on the loop's grid).
  void tick(uint64_t now_us);

  // Loop drivers report each cycle's work time and start jitter here.
  void record_cycle_timing(uint32_t work_us, uint32_t jitter_us, bool overrun);

  void set_observer(AppObserver* observer) { observer_ = observer; }

  // Parameter access for the console and tools; changes apply live.
  const Params& params() const { return params_; }
  [[nodiscard]] Status set_param(ParamId id, float value);
  void apply_params(const Params& params);
  [[nodiscard]] Status save_params();
  [[nodiscard]] Status load_params();

  void reset_filter();
  // Zeroes every counter the console shows: input validation and loop timing,
  // CAN bus driver, publisher and HIL decoder, and - as offsets from this moment,
  // since the estimator counts monotonically - the navigator's counters
  // (nav_counters()). CAN diagnostics frames keep carrying the monotonic counts.
  void reset_stats();
  // The navigator's diagnostics with its counters taken since the last reset_stats().
  NavDiagnostics nav_counters() const;
  static constexpr size_t kNavCounters = 12;  // leading uint32_t counters of NavDiagnostics

  const AppStats& stats() const { return stats_; }
  const Navigator& navigator() const { return nav_; }
  const NavOutput& last_output() const { return last_output_; }
  uint64_t last_tick_us() const { return last_tick_us_; }
  hal::Board& board() { return board_; }
  Console& console() { return console_; }
  const can::CanTxStats& can_tx_stats() const { return can_tx_.stats(); }
  const can::CanSensorStats& can_rx_stats() const { return can_decoder_.stats(); }

 private:
  void drain_sensors(uint64_t now_us);
  void drain_can_sensors(uint64_t now_us);
  void accept_can_sample(const can::CanSensorSample& sample, uint64_t now_us);
  [[nodiscard]] bool accept_imu(const ImuSample& imu, uint64_t now_us, SourceStats& src);
  [[nodiscard]] bool accept_uwb(const UwbRange& r, uint64_t now_us, SourceStats& src);
  void process_in_time_order();
  void handle_range(const UwbRange& r);
  void drain_gnss(uint64_t now_us);
#if UWBNAV_GNSS
  void fuse_gnss(const GnssFix& fix, uint64_t now_us);  // validate, fuse, report
#endif
#if UWBNAV_COOP
  // Neighbour states from the board's source (recordings), before the cycle's
  // ranges so that a range finds the state broadcast before it.
  void drain_neighbours(uint64_t now_us);
  void accept_neighbour(const NeighbourState& s, uint64_t now_us);
  void publish_coop_state();
#endif

  hal::Board& board_;
  Params params_;
  Navigator nav_;
  InputValidator validator_;
  can::CanPublisher can_tx_;
  can::CanDiag can_diag_;
  can::CanSensorDecoder can_decoder_;
  bool hil_rx_enabled_ = false;
  can::CanSensorSample can_pending_[kMaxCanPending];  // HIL samples due in a later cycle
  size_t can_pending_count_ = 0;
#if UWBNAV_GNSS
  GnssFix can_gnss_[kMaxGnssPerCycle];  // GNSS_Fix* decoded this cycle, fused in drain_gnss()
  size_t can_gnss_count_ = 0;
#endif
  AppStats stats_;
  uint32_t nav_base_[kNavCounters];  // navigator counters at the last reset_stats() (zeroed by init())
  AppObserver* observer_ = nullptr;
  NavOutput last_output_;
  uint64_t last_tick_us_ = 0;
  bool initialised_ = false;
  Console console_{*this};  // serial shell; polled at the end of every tick

  // Per-cycle staging, sorted by sensor time before reaching the estimator.
  ImuSample imu_buf_[kMaxImuPerCycle];
  size_t imu_count_ = 0;
  UwbRange uwb_buf_[kMaxUwbPerCycle];
  size_t uwb_count_ = 0;
};

}  // namespace uwbnav
