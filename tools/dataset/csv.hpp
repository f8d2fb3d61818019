// Internal CSV machinery of format v1 (docs/dataset-format.md): the line
// walker (over text in memory or streamed from a plain/gzip file with a fixed
// buffer), a table reader that checks the header, skips comments and splits
// rows into strictly parsed cells, and a line builder that writes numbers
// which read back bit-exactly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/text_source.hpp"

namespace uwbnav::dataset::csv {

// Columns of one table: `required` always present, then any leading part of
// `optional` (trailing optional columns may be left out, order is fixed).
struct Columns {
  std::vector<const char*> required;
  std::vector<const char*> optional;
  bool optional_as_group = false;  // all optional columns or none (truth.csv quaternion)
};

// Reads a whole file into memory. kNotFound when it does not exist, kIoError
// when it cannot be read.
[[nodiscard]] Status read_file(const std::string& path, std::string& out);

// Appends a warning "name:line: reason" ("name: reason" when line is 0) to
// `report`, respecting the cap.
void warn(ReadReport& report, const std::string& name, size_t line, const std::string& reason);

// The line walker of every format v1 file: yields the physical lines of a
// text held in memory (view) or streamed from a file (open; plain or .gz),
// each without its '\n', a trailing CR and, on line 1, a UTF-8 byte-order
// mark. Streaming keeps one fixed buffer (kChunk bytes, grown only for a
// single line longer than that), so its memory does not depend on the
// number of lines.
class LineReader {
 public:
  static constexpr size_t kChunk = 1U << 16;  // bytes read per refill

  LineReader() = default;
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  // Walks `text` in place (it must outlive the reader).
  void view(const std::string& text);
  // Streams `path` (or `path`.gz, see TextSource::open).
  [[nodiscard]] Status open(const std::string& path);

  // The next line as [begin, end), valid until the next call; `line()`
  // counts from 1. False at the end of the text or on a read error (status()).
  bool next(const char*& begin, const char*& end);

  size_t line() const { return line_no_; }
  // View mode: resume at byte `pos` of the text, `line_no` lines already walked.
  void skip_to(size_t pos, size_t line_no) {
    pos_ = pos;
    line_no_ = line_no;
  }
  // View mode: byte offset of the next line.
  size_t position() const { return pos_; }
  // kOk, or kIoError after a read error / truncated or corrupt .gz (error() says why).
  Status status() const { return source_ ? source_->status() : Status::kOk; }
  const std::string& error() const;
  // Bytes currently held for lines (the streaming buffer's capacity).
  size_t buffer_bytes() const { return buf_.capacity(); }

 private:
  bool refill();

  const char* data_ = nullptr;  // view: the text; stream: buf_.data()
  size_t size_ = 0;             // bytes valid at data_
  size_t pos_ = 0;              // start of the next line
  size_t line_no_ = 0;
  std::unique_ptr<TextSource> source_;  // set when streaming
  std::string buf_;
  bool eof_ = false;
};

// The next physical line of `text` from `pos` (advanced past it), as
// LineReader yields it; `line_no` counts from 1. False at the end of the text.
bool next_line(const std::string& text, size_t& pos, size_t& line_no, std::string& line);

// Printable, truncated copy of raw file bytes for messages.
std::string quote(const char* p, size_t n);

// Walks the rows of one table, held in memory or streamed (LineReader).
// Usage: header(), then next_row() until false; inside a row, the parse_*
// calls return false and set reason() when the cell is malformed. Only the
// current row is held.
class Table {
 public:
  // Over `text` in memory (it must outlive the table).
  Table(const std::string& text, std::string name);
  // Streamed from `lines` (already opened; it must outlive the table).
  Table(LineReader& lines, std::string name);
  Table(const Table&) = delete;
  Table& operator=(const Table&) = delete;

  // Finds the header (first line that is neither blank nor a '#' comment) and
  // checks it against `cols`. kOk: columns() set. kEmpty: no header line at
  // all. kInvalidArgument: wrong header; `error` says why ("file:line: ...").
  [[nodiscard]] Status header(const Columns& cols, std::string& error);

  // Advances to the next data row (blank lines and comments are passed over).
  bool next_row();

  size_t line() const { return line_no_; }
  const std::string& name() const { return name_; }
  size_t columns() const { return names_.size(); }
  size_t cells() const { return cells_.size(); }

  // True when the row's cell count matches the header; sets reason() otherwise.
  bool check_cell_count();
  // True when the cell is empty (or beyond the header's columns).
  bool empty(size_t col) const;
  // Strict finite number; the whole cell must parse. Empty cells are an error.
  bool parse_double(size_t col, double& out);
  // As parse_double, and the value must be finite as a float.
  bool parse_float(size_t col, float& out);
  // Empty cell -> NaN, else as parse_float.
  bool parse_float_or_nan(size_t col, float& out);
  // Non-negative integer <= max_value (no sign, no fraction).
  bool parse_uint(size_t col, uint64_t max_value, uint64_t& out);
  // t_s >= 0 converted with seconds_to_us; also checks the time does not go
  // backwards against the last accepted row (call accept_time() once the row is kept).
  bool parse_time(size_t col, uint64_t& t_us);
  void accept_time(uint64_t t_us);

  const std::string& reason() const { return reason_; }

 private:
  void split(const char* begin, const char* end);
  void cell(size_t col, const char*& b, const char*& e) const;
  bool fail(size_t col, const char* what);

  LineReader own_;      // the reader of a table held in memory
  LineReader& lines_;   // own_ or the caller's streaming reader
  std::string name_;
  size_t line_no_ = 0;
  std::vector<std::string> names_;
  std::vector<std::pair<const char*, const char*>> cells_;
  std::string reason_;
  uint64_t last_t_us_ = 0;
  bool have_time_ = false;
};

// Builds one output line; numbers are written in the shortest form that reads
// back to the same float/double (std::to_chars), NaN as an empty cell.
class LineBuilder {
 public:
  void clear() { s_.clear(); }
  LineBuilder& sep() {
    s_.push_back(',');
    return *this;
  }
  LineBuilder& time(uint64_t t_us);
  LineBuilder& f32(float v);
  LineBuilder& f64(double v);
  LineBuilder& u64(uint64_t v);
  LineBuilder& i64(int64_t v);
  LineBuilder& text(const char* t) {
    s_ += t;
    return *this;
  }
  // Appends '\n' and writes the line; false on a write error.
  bool flush_to(std::FILE* f);

 private:
  std::string s_;
};

// Joins column names with commas (header lines).
std::string join(const Columns& cols, size_t num_optional);

}  // namespace uwbnav::dataset::csv
