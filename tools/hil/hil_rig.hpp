// The HIL test bench: plays a recording in real time into a firmware over a
// CAN link (HIL sensor frames), reads the firmware's CAN output back, and
// summarises latency, jitter, dropped frames and position error (docs/hil.md).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "hal/host/candump_log.hpp"
#include "hal/host/socketcan_bus.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/hil/output_monitor.hpp"
#include "tools/hil/sensor_stream.hpp"

namespace uwbnav::hil {

struct RigOptions {
  double speed = 1.0;                 // playback speed (1.0 = real time; docs/hil.md for other values)
  uint64_t lead_us = 300000;          // first sample this long after the firmware was seen [us]
  uint64_t tail_us = 500000;          // keep reading this long after the last sample [us]
  uint64_t wait_output_us = 10000000; // give up when no UWBNAV_NavTime arrives within this [us]
  uint64_t align_us = 500000;         // clock alignment window (align_clock) [us]
  bool align_clock = false;           // estimate the firmware clock offset from UWBNAV_NavTime
  const volatile bool* stop = nullptr;         // set (e.g. by SIGINT) to end playback early
  hal::CandumpLogWriter* rx_log = nullptr;     // every frame read from the bus
  hal::CandumpLogWriter* tx_log = nullptr;     // every frame the rig sent
  std::FILE* progress = nullptr;               // a progress line every progress_every_us while playing
  uint64_t progress_every_us = 5000000;
};

// What one run produced; the stream and monitor stay alive for the report.
struct RigRun {
  std::unique_ptr<SensorStream> stream;
  std::unique_ptr<OutputMonitor> monitor;
  int64_t clock_offset_us = 0;   // firmware clock - rig clock (CLOCK_MONOTONIC) [us]
  uint64_t imu_sent = 0;         // samples fully sent (every frame accepted)
  uint64_t uwb_sent = 0;
  uint64_t frames_sent = 0;
  uint64_t tx_dropped = 0;       // frames the link refused (kWouldBlock)
  uint64_t tx_failed = 0;        // kIoError (link closed, bus-off)
  uint64_t frames_received = 0;  // while playing (plus the tail)
  uint64_t send_late_max_us = 0; // worst lateness of the rig's own sends vs sample time [us]
  double played_s = 0.0;         // playback wall time [s]
  bool interrupted = false;      // stop flag ended the playback early
  bool link_closed = false;      // the firmware went away
};

// Plays `rec` through `bus` (a connected link or SocketCAN interface) in real
// time. kOk: `run` filled. Failure: `error` says why (no firmware output, link down).
[[nodiscard]] Status run_rig(const dataset::Recording& rec, hal::SocketCanBus& bus, const RigOptions& options,
                             RigRun& run, std::string* error);

// Statistics of a series (NaN fields when empty).
struct SeriesStats {
  size_t n = 0;
  double mean = 0.0, std = 0.0, min = 0.0, p50 = 0.0, p95 = 0.0, p99 = 0.0, max = 0.0;
};
SeriesStats series_stats(const std::vector<double>& v);

struct HilReport {
  std::string recording;
  std::string link;                 // "unix:PATH" or "can:IF"
  double speed = 1.0;
  double played_s = 0.0;
  int64_t clock_offset_us = 0;
  uint64_t imu_sent = 0, uwb_sent = 0, frames_sent = 0, tx_dropped = 0, tx_failed = 0;
  uint64_t send_late_max_us = 0;
  uint64_t frames_received = 0;
  SeriesStats latency_ms;           // end-to-end latency (docs/hil.md)
  std::vector<uint32_t> latency_hist;  // end-to-end latency per bin of the firmware's cycle histogram (kLatencyBinUpperUs)
  SeriesStats period_ms;            // PosXY inter-arrival
  double period_max_dev_ms = 0.0;   // max |inter-arrival - 10 ms|
  std::vector<MessageCheck> messages;
  uint32_t missing = 0;             // output frames lost (counter gaps)
  uint32_t e2e_failures = 0;        // CRC / length / counter-value failures
  uint32_t group_mismatches = 0;
  uint32_t other_frames = 0;
  bool have_diag = false;
  uint64_t fw_overruns = 0;         // from UWBNAV_Diag (saturating 65535)
  uint32_t fw_input_rejects = 0;    // from UWBNAV_Diag
  size_t solutions = 0;             // received solutions
  eval::AccuracyStats hil;          // received positions vs truth
  bool have_lockstep = false;
  eval::AccuracyStats lockstep;     // same recording, lockstep replay, vs truth
  bool interrupted = false;
  bool link_closed = false;
  std::string firmware_latency;     // the spawned firmware's own cycle-latency histogram (its exit summary)
};

// Pass/fail bounds of `uwbnav hil --max-*` (a negative bound: not checked).
struct HilLimits {
  double max_missing = -1.0;         // missing + E2E failures + group mismatches
  double max_latency_ms = -1.0;      // the largest end-to-end latency
  double max_latency_p99_ms = -1.0;  // the 99th percentile of the end-to-end latency
  double max_rmse_m = -1.0;          // horizontal RMSE of the received positions
};

// One line per requested check, "CHECK passed: ..." or "CHECK FAILED: ...",
// naming the quantity, its value and the bound; *failures counts the failed ones.
std::vector<std::string> check_report(const HilReport& r, const HilLimits& limits, int* failures);

// Builds the report. lockstep: run the same recording in lockstep for reference.
HilReport build_report(const dataset::Recording& rec, const RigRun& run, bool lockstep);
void print_report(std::FILE* out, const HilReport& r);
[[nodiscard]] Status write_report_markdown(const std::string& path, const HilReport& r);

}  // namespace uwbnav::hil
