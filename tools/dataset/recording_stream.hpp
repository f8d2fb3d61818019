// Streaming reader of a format v1 recording (docs/dataset-format.md): the
// small tables (meta.ini, anchors.csv, tags.csv and the optional gnss.csv and
// neighbours.csv, a few rows per second) are read whole when the recording is opened; uwb.csv,
// imu.csv and truth.csv (or their .csv.gz) are walked one row at a time with
// one row of look-ahead, so the memory they hold does not depend on the
// recording's length. read_recording() is built on it: both
// share the row parsers and the validation (bad rows skipped with "file:line: reason").
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "estimator/types.hpp"
#include "tools/dataset/csv.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::dataset {

// Row parsers of the time-series tables: true and `out` filled for a good row;
// false with `reason` (or table.reason()) for a bad one. They call accept_time().
bool parse_row(csv::Table& t, UwbRow& out, std::string& reason);
bool parse_row(csv::Table& t, ImuSample& out, std::string& reason);
bool parse_row(csv::Table& t, TruthRow& out, std::string& reason);
// gnss.csv: a fix-0 ("no fix") row is a good row with out.fix == kNone and no
// position; read_gnss() counts it as read but keeps it out of its output.
bool parse_row(csv::Table& t, GnssFix& out, std::string& reason);
// neighbours.csv: checks one row on its own (ids, covariance, latency, velocity,
// coop flag); it does not call accept_time(): the rows only have to keep time
// order per vehicle, which read_neighbours() checks.
bool parse_row(csv::Table& t, NeighbourState& out, std::string& reason);

inline uint64_t row_time_us(const UwbRow& r) { return r.range.t_us; }
inline uint64_t row_time_us(const ImuSample& s) { return s.t_us; }
inline uint64_t row_time_us(const TruthRow& r) { return r.t_us; }

// Rows of one time-series table in time order, one at a time, from a file or memory.
template <typename Row>
class RowFeed {
 public:
  virtual ~RowFeed() = default;
  // The next row without consuming it; nullptr at the end.
  virtual const Row* peek() const = 0;
  // Consumes the next row into `out`; false at the end.
  virtual bool next(Row& out) = 0;
};

// A RowFeed over rows held in memory (they must outlive the feed).
template <typename Row>
class VectorFeed final : public RowFeed<Row> {
 public:
  explicit VectorFeed(const std::vector<Row>& rows) : rows_(rows) {}
  const Row* peek() const override { return next_ < rows_.size() ? &rows_[next_] : nullptr; }
  bool next(Row& out) override {
    if (next_ >= rows_.size()) return false;
    out = rows_[next_++];
    return true;
  }

 private:
  const std::vector<Row>& rows_;
  size_t next_ = 0;
};

// The good rows of one time-series table, in file order, one at a time.
template <typename Row>
class RowStream final : public RowFeed<Row> {
 public:
  RowStream() = default;
  RowStream(const RowStream&) = delete;
  RowStream& operator=(const RowStream&) = delete;

  // Opens dir/file (or file.gz), checks the header and reads ahead to the
  // first good row. kOk also when an optional file is absent or has no header
  // (present() false; the latter warned about). Otherwise report.error says why.
  [[nodiscard]] Status open(const std::string& dir, const char* file, const csv::Columns& cols, bool required,
                            ReadReport& report);

  // The next good row without consuming it; nullptr at the end (or after a read error).
  const Row* peek() const override { return have_ ? &row_ : nullptr; }
  // Consumes the next good row into `out`; false at the end.
  bool next(Row& out) override;

  bool present() const { return table_ != nullptr; }
  const char* file() const { return file_; }
  size_t rows_delivered() const { return delivered_; }
  // Time of the last row delivered by next() [us]; 0 before the first.
  uint64_t last_t_us() const { return last_t_us_; }
  // kOk, or kIoError when the file could not be read to its end (then error()
  // names it: "imu.csv: cannot be read (imu.csv.gz: truncated gzip stream ...)").
  Status status() const { return table_ != nullptr ? lines_.status() : Status::kOk; }
  std::string error() const;
  // Bytes of line buffer held (independent of the number of rows).
  size_t buffer_bytes() const { return lines_.buffer_bytes(); }

 private:
  void advance();

  csv::LineReader lines_;
  std::unique_ptr<csv::Table> table_;
  ReadReport* report_ = nullptr;
  const char* file_ = "";
  Row row_{};
  bool have_ = false;
  size_t delivered_ = 0;
  uint64_t last_t_us_ = 0;
  std::string reason_;
};

// One recording opened for streaming.
class RecordingStream {
 public:
  // Reads meta.ini, anchors.csv, tags.csv, gnss.csv and neighbours.csv and opens uwb.csv,
  // imu.csv and (when `with_truth`) truth.csv. Fails as read_recording does for a missing
  // directory or required file, a wrong header or no usable anchor; warnings
  // go to `report`, which must outlive the stream (rows read later add theirs).
  [[nodiscard]] Status open(const std::string& dir, ReadReport& report, bool with_truth = true);

  std::string name() const { return recording_name(meta, dir); }
  // The first read error of the time-series streams ("imu.csv: cannot be read (...)"), empty when none.
  std::string read_error() const;

  std::string dir;
  std::map<std::string, std::string> meta;
  SiteConfig site;  // has_imu: imu.csv holds at least one good row
  RowStream<UwbRow> uwb;
  RowStream<ImuSample> imu;
  RowStream<TruthRow> truth;
  std::vector<GnssFix> gnss;  // gnss.csv read whole at open, in arrival (rx_t_us) order; empty when absent
  // neighbours.csv read whole at open, in arrival (rx_t_us) order; empty when absent.
  std::vector<NeighbourState> neighbours;
};

// Reads the optional gnss.csv (or gnss.csv.gz) of `dir` whole: good rows with a
// fix, stably sorted by rx_t_us; bad rows skipped with a "gnss.csv:line: reason"
// warning. kOk with `out` empty when the file is absent. Fails (report.error)
// on a wrong header or a read error, as for imu.csv.
[[nodiscard]] Status read_gnss(const std::string& dir, std::vector<GnssFix>& out, ReadReport& report);

// Reads the optional neighbours.csv (or neighbours.csv.gz) of `dir` whole: good
// rows, stably sorted by rx_t_us; bad rows (a row whose t_s goes backwards for
// its vehicle included) skipped with a "neighbours.csv:line: reason" warning.
// kOk with `out` empty when the file is absent. Fails (report.error) on a wrong
// header or a read error, as for imu.csv.
[[nodiscard]] Status read_neighbours(const std::string& dir, std::vector<NeighbourState>& out, ReadReport& report);

// Reads meta.ini, anchors.csv and tags.csv of `dir` into `meta` and `site`
// (the part of a recording read whole). Fails as read_recording does.
[[nodiscard]] Status read_site(const std::string& dir, std::map<std::string, std::string>& meta, SiteConfig& site,
                               ReadReport& report);

}  // namespace uwbnav::dataset
