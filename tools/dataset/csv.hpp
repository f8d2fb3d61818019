// Internal CSV machinery of format v1 (docs/dataset-format.md): a table reader
// that checks the header, skips comments and splits rows into strictly parsed
// cells, and a line builder that writes numbers which read back bit-exactly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "tools/dataset/recording.hpp"

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

// The next physical line of `text` from `pos` (advanced past it) with a
// trailing CR and, on line 1, a UTF-8 byte-order mark removed; `line_no`
// counts from 1. False at the end of the text.
bool next_line(const std::string& text, size_t& pos, size_t& line_no, std::string& line);

// Printable, truncated copy of raw file bytes for messages.
std::string quote(const char* p, size_t n);

// Walks the rows of one table held in memory. Usage: header(), then
// next_row() until false; inside a row, the parse_* calls return false and set
// reason() when the cell is malformed.
class Table {
 public:
  Table(const std::string& text, std::string name);

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
  bool next_line(const char*& begin, const char*& end);
  void split(const char* begin, const char* end);
  void cell(size_t col, const char*& b, const char*& e) const;
  bool fail(size_t col, const char* what);

  const std::string& text_;
  std::string name_;
  size_t pos_ = 0;
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
