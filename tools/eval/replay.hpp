// Lockstep replay: runs the firmware App over a format v1 recording on the
// host replay board (clock follows the recording, as fast as the CPU allows,
// bit-for-bit deterministic), collecting and optionally writing the outputs.
// The recording comes whole from memory or streamed from its directory
// (dataset::RecordingStream); outputs are written as they are produced and can
// be evaluated on the fly through a ReplaySink.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "estimator/navigator.hpp"
#include "firmware/app_stats.hpp"
#include "hal/hal.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/recording_stream.hpp"

namespace uwbnav::eval {

// Receives every output epoch of a replay as it is produced (streaming
// evaluation). Called on the replay's output thread, in epoch order, never
// after run_replay returned: it must not share unguarded state with the
// recording the loop reads (e.g. the ReadReport of its streams).
class ReplaySink {
 public:
  virtual ~ReplaySink() = default;
  // Epochs arrive in time order, one per firmware cycle.
  virtual void on_estimate(const dataset::EstimateRow& e) = 0;
};

struct ReplayOptions {
  std::string out_dir;        // write estimates.csv, ranges.csv, can.log here; empty: nothing written
  bool keep_in_memory = true; // keep estimates/ranges in ReplayResult
  std::vector<std::pair<std::string, float>> params;  // overrides by name, applied after defaults
  bool progress = false;      // progress line on stderr for long runs
  ReplaySink* sink = nullptr; // also receives every epoch, on the output thread (not owned)
};

struct ReplayResult {
  uint64_t cycles = 0;
  double wall_s = 0.0;                        // host wall time of the loop [s]
  AppStats stats;
  NavDiagnostics diag;
  uint64_t ranges_used = 0;
  uint64_t ranges_rejected = 0;
  uint64_t can_frames = 0;                    // frames the firmware sent
  uint64_t epochs = 0;                        // output epochs
  uint64_t solution_epochs = 0;               // epochs carrying a position (status valid or degraded)
  uint64_t gnss_fused = 0;                    // GNSS fixes the estimator fused
  uint64_t gnss_rejected = 0;                 // GNSS fixes it refused (any GnssVerdict but fused)
  std::vector<dataset::EstimateRow> estimates;
  std::vector<RangeReport> ranges;
};

// kOk on success; on failure `error` says why (bad parameter override, output not writable).
[[nodiscard]] Status run_replay(const dataset::Recording& rec, const ReplayOptions& options, ReplayResult& result,
                                std::string* error);

// The same over a recording streamed from its directory: IMU and UWB rows are
// read as the loop reaches their time (memory independent of the length).
// Bad rows met on the way are warned about in the stream's ReadReport; a read
// error (truncated .gz) ends that stream early: check rec.read_error() after.
[[nodiscard]] Status run_replay(dataset::RecordingStream& rec, const ReplayOptions& options, ReplayResult& result,
                                std::string* error);

// NavOutput -> the row format of estimates.csv (for in-memory evaluation).
dataset::EstimateRow to_estimate_row(const NavOutput& out);

}  // namespace uwbnav::eval
