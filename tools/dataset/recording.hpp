// Host-side model of a format v1 recording (docs/dataset-format.md) and of the
// replay outputs, with the reader and writers. Host only: uses the heap and files.
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav::dataset {

namespace csv {
class LineBuilder;
}

// One uwb.csv row: the range plus its evaluation-only label.
struct UwbRow {
  UwbRange range;
  int8_t nlos_label = -1;  // 1 NLOS, 0 LOS, -1 unknown. Never read by the estimator.
};

// One truth.csv row (body origin in the navigation frame).
struct TruthRow {
  uint64_t t_us = 0;
  double pos_nav_m[3] = {0, 0, 0};
  bool has_attitude = false;
  double q_nav_body[4] = {1, 0, 0, 0};  // Hamilton, scalar first, body -> nav
};

struct Recording {
  std::string dir;                          // where it was read from (may be empty)
  std::map<std::string, std::string> meta;  // meta.ini key = value
  SiteConfig site;                          // anchors, tags, platform, gravity, has_imu
  // meta.ini keys as read. Simulator facts such as uwb_sigma_m (the true noise
  // level) stay here, for evaluation only: nothing in this map reaches the firmware.
  std::vector<ImuSample> imu;               // empty for UWB-only recordings
  std::vector<UwbRow> uwb;
  std::vector<TruthRow> truth;              // empty when the recording has no truth
  std::vector<GnssFix> gnss;                // gnss.csv, in arrival (rx_t_us) order; empty without a receiver
  std::vector<NeighbourState> neighbours;   // neighbours.csv, in arrival (rx_t_us) order; empty without neighbours
  std::string name() const;                 // meta "name" or the directory's last component
};

// Meta "name" or the directory's last component.
std::string recording_name(const std::map<std::string, std::string>& meta, const std::string& dir);

// What the reader skipped, for the warning lines and the tests.
struct ReadReport {
  size_t rows_read = 0;       // data rows accepted over all files
  size_t rows_skipped = 0;    // data rows rejected over all files
  std::vector<std::string> warnings;  // "uwb.csv:123: <reason>", capped (see kMaxWarnings)
  size_t warnings_dropped = 0;        // warnings not stored because the cap was reached
  std::string error;                  // "uwb.csv:1: <reason>" when a read fails (non-kOk)
  static constexpr size_t kMaxWarnings = 200;
};

// Prints the warnings (and how many were dropped) one per line to `out`.
void print_warnings(const ReadReport& report, std::FILE* out);

// Reads a format v1 directory whole (for the streaming reader see
// recording_stream.hpp, which this is built on). Bad rows (unparsable, NaN/Inf, wrong column
// count, backwards time, negative ids) are skipped, counted and warned about
// with file and line number; they never reach `out`. Fails (non-kOk) only when
// a required file is missing/unreadable, a header is wrong, or anchors.csv
// yields no usable anchor.
// Each table X.csv may be stored gzip-compressed as X.csv.gz (read when X.csv
// is absent); a truncated or corrupt .gz fails the read like an unreadable file.
[[nodiscard]] Status read_recording(const std::string& dir, Recording& out, ReadReport& report);

// Input streams that stop early: with both imu.csv and uwb.csv present, a stream
// whose last sample comes more than kStreamEndToleranceUs before the other's
// (a truncated file, a sensor that died). One line per such stream, e.g.
// "imu.csv: ends at t=30.000 s, 29.990 s before uwb.csv (last 59.990 s): input stream ended early".
constexpr uint64_t kStreamEndToleranceUs = 1000000;
std::vector<std::string> streams_ended_early(const Recording& rec);
// The same from the last timestamps of both streams (both present and non-empty).
std::vector<std::string> streams_ended_early(uint64_t imu_end_us, uint64_t uwb_end_us);

// Writes `rec` as a format v1 directory (creating it). Floats are written with
// enough digits to round-trip the estimator's input exactly.
[[nodiscard]] Status write_recording(const std::string& dir, const Recording& rec);

// Streaming writers for the replay outputs (estimates.csv, ranges.csv).
class EstimatesWriter {
 public:
  EstimatesWriter();
  ~EstimatesWriter();
  EstimatesWriter(const EstimatesWriter&) = delete;
  EstimatesWriter& operator=(const EstimatesWriter&) = delete;
  [[nodiscard]] Status open(const std::string& path);
  [[nodiscard]] Status write(const NavOutput& out);
  [[nodiscard]] Status close();

 private:
  std::FILE* f_ = nullptr;
  std::unique_ptr<csv::LineBuilder> line_;  // reused for every row
};

class RangesWriter {
 public:
  RangesWriter();
  ~RangesWriter();
  RangesWriter(const RangesWriter&) = delete;
  RangesWriter& operator=(const RangesWriter&) = delete;
  [[nodiscard]] Status open(const std::string& path);
  // `nlos_label` is not written (ranges.csv's nlos column is the decision).
  [[nodiscard]] Status write(const RangeReport& report);
  [[nodiscard]] Status close();

 private:
  std::FILE* f_ = nullptr;
  std::unique_ptr<csv::LineBuilder> line_;  // reused for every row
};

// Readers for replay outputs (evaluation, tests). Rows that do not parse are skipped and counted.
struct EstimateRow {
  uint64_t t_us = 0;
  double pos_nav_m[3] = {0, 0, 0};
  double vel_nav_mps[3] = {0, 0, 0};
  double q_nav_body[4] = {1, 0, 0, 0};
  double pos_sigma_m[3] = {0, 0, 0};
  int status = 0;
  int mode = 0;              // NavMode (in memory only; estimates.csv has no mode column)
  double pos_xy_corr = 0.0;  // x/y position error correlation (in memory only)
};
[[nodiscard]] Status read_estimates(const std::string& path, std::vector<EstimateRow>& out, ReadReport& report);
[[nodiscard]] Status read_ranges(const std::string& path, std::vector<RangeReport>& out, ReadReport& report);

// Microseconds <-> seconds as used in the CSV files.
uint64_t seconds_to_us(double t_s);
double us_to_seconds(uint64_t t_us);

}  // namespace uwbnav::dataset
