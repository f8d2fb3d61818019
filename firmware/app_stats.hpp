// Firmware-level counters: input validation rejects per reason and source, and
// loop timing. Read by the console (`stats`), CAN diagnostics and reports.
#pragma once

#include <cstdint>

#include "estimator/params.hpp"  // UWBNAV_GNSS

namespace uwbnav {

// Why a frame was rejected before reaching the estimator. Stable order (console, CAN).
enum class RejectReason : uint8_t {
  kNotFinite = 0,     // NaN or Inf in any field
  kOutOfRange,        // outside physical limits (params in.*, uwb.min/max_range; GNSS sigma, latency)
  kUnknownAnchor,     // anchor id not in the site table
  kUnknownTag,        // tag id not in the site table
  kDuplicate,         // same timestamp (and anchor/tag) as an accepted frame
  kOutOfOrder,        // timestamp older than the last accepted frame of that stream
  kStale,             // older than the loop time by more than in.stale_us
  kFuture,            // timestamp ahead of the loop clock (clock fault)
  kCount
};

constexpr const char* reject_reason_name(RejectReason r) {
  switch (r) {
    case RejectReason::kNotFinite: return "not_finite";
    case RejectReason::kOutOfRange: return "out_of_range";
    case RejectReason::kUnknownAnchor: return "unknown_anchor";
    case RejectReason::kUnknownTag: return "unknown_tag";
    case RejectReason::kDuplicate: return "duplicate";
    case RejectReason::kOutOfOrder: return "out_of_order";
    case RejectReason::kStale: return "stale";
    case RejectReason::kFuture: return "future";
    case RejectReason::kCount: break;
  }
  return "unknown";
}

constexpr uint32_t kNumRejectReasons = static_cast<uint32_t>(RejectReason::kCount);

struct SourceStats {
  uint32_t received = 0;                     // frames read from the HAL
  uint32_t accepted = 0;                     // passed validation, handed to the estimator
  uint32_t rejected[kNumRejectReasons] = {}; // per reason
  uint32_t io_errors = 0;                    // HAL poll() returned kIoError
  uint32_t rejected_total() const {
    uint32_t n = 0;
    for (uint32_t r : rejected) n += r;
    return n;
  }
};

// Boards whose loop driver reports no cycle timing (the lockstep MPS2 image) build
// without the histogram (flash).
#ifndef UWBNAV_LOOP_HISTOGRAM
#define UWBNAV_LOOP_HISTOGRAM 1
#endif

// Cycle-latency histogram (as rt-tests' cyclictest, in coarse bins): the time
// from a cycle's deadline to the end of its work [us] — the wake-up latency
// plus the work. Bin i counts latencies <= kLatencyBinUpperUs[i]; the last bin
// everything above. A latency above the period is an overrun.
constexpr uint32_t kLatencyBinUpperUs[] = {50, 100, 200, 500, 1000, 2000, 5000, 10000, 20000, 50000};
constexpr uint32_t kNumLatencyBins = sizeof kLatencyBinUpperUs / sizeof kLatencyBinUpperUs[0] + 1;

constexpr uint32_t latency_bin(uint32_t latency_us) {
  uint32_t i = 0;
  while (i + 1 < kNumLatencyBins && latency_us > kLatencyBinUpperUs[i]) ++i;
  return i;
}

struct LoopStats {
  uint64_t cycles = 0;
  uint64_t overruns = 0;          // cycles whose work exceeded the period
  uint32_t cycle_min_us = 0;      // work time per cycle [us]
  uint32_t cycle_max_us = 0;
  uint64_t cycle_sum_us = 0;      // for the average
  uint32_t jitter_max_us = 0;     // max |actual start - deadline| [us] (real-time driver)
#if UWBNAV_LOOP_HISTOGRAM
  uint32_t latency_max_us = 0;    // max (end of work - deadline) [us]
  uint32_t latency_hist[kNumLatencyBins] = {};  // cycles per latency bin (kLatencyBinUpperUs)
#endif
  uint32_t avg_us() const { return cycles ? static_cast<uint32_t>(cycle_sum_us / cycles) : 0; }
};

struct AppStats {
  SourceStats imu;
  SourceStats uwb;
  SourceStats can_rx;             // HIL sensor frames received over CAN
#if UWBNAV_GNSS
  SourceStats gnss;               // GNSS fixes (CAN GNSS_Fix* and the board's GnssSource); io_errors
                                  // also counts CAN fixes beyond kMaxGnssPerCycle in one cycle
#endif
#if UWBNAV_COOP
  // Neighbour vehicles' broadcast states (board NeighbourSource or CAN V2X_Neighbour*).
  // Ranges to their tags are counted with the other ranges (uwb, can_rx).
  SourceStats neighbours;
#endif
  LoopStats loop;
};

}  // namespace uwbnav
