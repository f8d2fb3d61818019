// Format v1 CSV table reader (header check, comments, strict cells) and the
// bit-exact number writer used by every format v1 file.
#include "tools/dataset/csv.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <system_error>

namespace uwbnav::dataset::csv {

namespace {

constexpr size_t kQuoteMax = 40;  // characters of a bad cell echoed in a warning

bool is_space(char c) { return c == ' ' || c == '\t'; }

void trim(const char*& b, const char*& e) {
  while (b < e && is_space(*b)) ++b;
  while (e > b && is_space(e[-1])) --e;
}

}  // namespace

Status read_file(const std::string& path, std::string& out) {
  out.clear();
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return errno == ENOENT ? Status::kNotFound : Status::kIoError;
  char buf[1 << 16];
  Status st = Status::kOk;
  for (;;) {
    const size_t n = std::fread(buf, 1, sizeof buf, f);
    out.append(buf, n);
    if (n < sizeof buf) {
      if (std::ferror(f) != 0) st = Status::kIoError;
      break;
    }
  }
  std::fclose(f);
  return st;
}

void warn(ReadReport& report, const std::string& name, size_t line, const std::string& reason) {
  if (report.warnings.size() >= ReadReport::kMaxWarnings) {
    ++report.warnings_dropped;
    return;
  }
  if (line == 0) {
    report.warnings.push_back(name + ": " + reason);
  } else {
    report.warnings.push_back(name + ":" + std::to_string(line) + ": " + reason);
  }
}

void LineReader::view(const std::string& text) {
  source_.reset();
  buf_ = std::string();
  data_ = text.data();
  size_ = text.size();
  pos_ = 0;
  line_no_ = 0;
  eof_ = true;
}

Status LineReader::open(const std::string& path) {
  source_ = std::make_unique<TextSource>();
  buf_.reserve(kChunk);
  data_ = buf_.data();
  size_ = 0;
  pos_ = 0;
  line_no_ = 0;
  eof_ = false;
  return source_->open(path);
}

const std::string& LineReader::error() const {
  static const std::string kNone;
  return source_ ? source_->error() : kNone;
}

// Moves the unread tail to the front of the buffer and reads more; grows the
// buffer only when the tail (one unfinished line) already fills it.
bool LineReader::refill() {
  if (eof_) return false;
  const size_t tail = size_ - pos_;
  if (tail > 0 && pos_ > 0) std::memmove(&buf_[0], &buf_[pos_], tail);
  size_t cap = std::max(buf_.capacity(), kChunk);
  if (tail + kChunk / 4 > cap) cap *= 2;
  buf_.resize(cap);
  const size_t got = source_->read(&buf_[tail], cap - tail);
  buf_.resize(tail + got);
  data_ = buf_.data();
  size_ = tail + got;
  pos_ = 0;
  if (got == 0) eof_ = true;
  return got > 0;
}

bool LineReader::next(const char*& begin, const char*& end) {
  const char* nl = nullptr;
  for (;;) {
    if (pos_ < size_) {
      nl = static_cast<const char*>(std::memchr(data_ + pos_, '\n', size_ - pos_));
      if (nl != nullptr) break;
      // An unterminated last line counts only when the file was read to its
      // end: after a read error it is a fragment, never a row.
      if (eof_) {
        if (!ok(status())) return false;
        break;
      }
    } else if (eof_) {
      return false;
    }
    if (!refill() && pos_ >= size_) return false;
  }
  const char* b = data_ + pos_;
  const char* e = nl != nullptr ? nl : data_ + size_;
  pos_ = static_cast<size_t>((nl != nullptr ? nl + 1 : e) - data_);
  ++line_no_;
  if (e > b && e[-1] == '\r') --e;  // CRLF line endings
  if (line_no_ == 1 && e - b >= 3 && std::memcmp(b, "\xEF\xBB\xBF", 3) == 0) b += 3;  // UTF-8 BOM
  begin = b;
  end = e;
  return true;
}

bool next_line(const std::string& text, size_t& pos, size_t& line_no, std::string& line) {
  if (pos >= text.size()) return false;
  LineReader lines;
  lines.view(text);
  lines.skip_to(pos, line_no);
  const char* b = nullptr;
  const char* e = nullptr;
  lines.next(b, e);
  line.assign(b, e);
  pos = lines.position();
  line_no = lines.line();
  return true;
}

std::string quote(const char* p, size_t n) {
  std::string s = "'";
  for (size_t i = 0; i < n && i < kQuoteMax; ++i) {
    const auto c = static_cast<unsigned char>(p[i]);
    if (c >= 0x20 && c < 0x7F) {
      s.push_back(static_cast<char>(c));
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", c);
      s += hex;
    }
  }
  if (n > kQuoteMax) s += "...";
  s += "'";
  return s;
}

Table::Table(const std::string& text, std::string name) : lines_(own_), name_(std::move(name)) {
  own_.view(text);
}

Table::Table(LineReader& lines, std::string name) : lines_(lines), name_(std::move(name)) {}

void Table::split(const char* begin, const char* end) {
  cells_.clear();
  const char* b = begin;
  for (;;) {
    const char* comma = b;  // cells are short: a plain scan beats a memchr call per cell
    while (comma < end && *comma != ',') ++comma;
    if (comma == end) comma = nullptr;
    const char* e = comma != nullptr ? comma : end;
    const char* cb = b;
    const char* ce = e;
    trim(cb, ce);
    cells_.emplace_back(cb, ce);
    if (comma == nullptr) break;
    b = comma + 1;
  }
}

Status Table::header(const Columns& cols, std::string& error) {
  const char* b = nullptr;
  const char* e = nullptr;
  for (;;) {
    if (!lines_.next(b, e)) return Status::kEmpty;
    line_no_ = lines_.line();
    const char* tb = b;
    const char* te = e;
    trim(tb, te);
    if (tb == te || *tb == '#') continue;
    break;
  }
  split(b, e);
  names_.clear();
  for (const auto& c : cells_) names_.emplace_back(c.first, c.second);
  bool good = names_.size() >= cols.required.size() &&
              names_.size() <= cols.required.size() + cols.optional.size() &&
              (!cols.optional_as_group || names_.size() == cols.required.size() ||
               names_.size() == cols.required.size() + cols.optional.size());
  for (size_t i = 0; good && i < names_.size(); ++i) {
    const char* want =
        i < cols.required.size() ? cols.required[i] : cols.optional[i - cols.required.size()];
    good = names_[i] == want;
  }
  if (good) return Status::kOk;
  error = name_ + ":" + std::to_string(line_no_) + ": wrong header " +
          quote(b, static_cast<size_t>(e - b)) + ", expected '" + join(cols, 0) + "'";
  if (!cols.optional.empty()) {
    std::string opt;
    for (const char* o : cols.optional) opt += std::string(",") + o;
    error += " optionally followed by '" + opt + "'" +
             (cols.optional_as_group ? " (all of them or none)"
                                     : " (in this order; trailing ones may be left out)");
  }
  names_.clear();
  return Status::kInvalidArgument;
}

bool Table::next_row() {
  const char* b = nullptr;
  const char* e = nullptr;
  for (;;) {
    if (!lines_.next(b, e)) return false;
    line_no_ = lines_.line();
    const char* tb = b;
    const char* te = e;
    trim(tb, te);
    if (tb == te || *tb == '#') continue;
    break;
  }
  split(b, e);
  reason_.clear();
  return true;
}

bool Table::check_cell_count() {
  if (cells_.size() == names_.size()) return true;
  reason_ = "expected " + std::to_string(names_.size()) + " columns, got " +
            std::to_string(cells_.size());
  return false;
}

void Table::cell(size_t col, const char*& b, const char*& e) const {
  if (col >= cells_.size()) {
    b = e = nullptr;
    return;
  }
  b = cells_[col].first;
  e = cells_[col].second;
}

bool Table::empty(size_t col) const {
  const char* b = nullptr;
  const char* e = nullptr;
  cell(col, b, e);
  return b == e;
}

bool Table::fail(size_t col, const char* what) {
  const char* b = nullptr;
  const char* e = nullptr;
  cell(col, b, e);
  const std::string col_name = col < names_.size() ? names_[col] : "column " + std::to_string(col + 1);
  reason_ = col_name + ": " + what;
  if (b != e) reason_ += " " + quote(b, static_cast<size_t>(e - b));
  return false;
}

bool Table::parse_double(size_t col, double& out) {
  const char* b = nullptr;
  const char* e = nullptr;
  cell(col, b, e);
  if (b == e) return fail(col, "empty");
  if (*b == '+') ++b;
  double v = 0.0;
  const auto r = std::from_chars(b, e, v, std::chars_format::general);
  if (r.ec == std::errc::result_out_of_range) return fail(col, "out of range");
  if (r.ec != std::errc() || r.ptr != e) return fail(col, "unparsable number");
  if (!std::isfinite(v)) return fail(col, "not finite");
  out = v;
  return true;
}

bool Table::parse_float(size_t col, float& out) {
  double v = 0.0;
  if (!parse_double(col, v)) return false;
  if (std::fabs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
    return fail(col, "out of float range");
  }
  out = static_cast<float>(v);
  return true;
}

bool Table::parse_float_or_nan(size_t col, float& out) {
  if (empty(col)) {
    out = std::numeric_limits<float>::quiet_NaN();
    return true;
  }
  return parse_float(col, out);
}

bool Table::parse_uint(size_t col, uint64_t max_value, uint64_t& out) {
  const char* b = nullptr;
  const char* e = nullptr;
  cell(col, b, e);
  if (b == e) return fail(col, "empty");
  if (*b == '-') return fail(col, "negative");
  if (*b == '+') ++b;
  uint64_t v = 0;
  const auto r = std::from_chars(b, e, v, 10);
  if (r.ec == std::errc::result_out_of_range) return fail(col, "out of range");
  if (r.ec != std::errc() || r.ptr != e) return fail(col, "not a non-negative integer");
  if (v > max_value) return fail(col, "out of range");
  out = v;
  return true;
}

bool Table::parse_time(size_t col, uint64_t& t_us) {
  double t_s = 0.0;
  if (!parse_double(col, t_s)) return false;
  if (t_s < 0.0) return fail(col, "negative time");
  // 1.8e13 s keeps t_s * 1e6 inside uint64_t with margin (and is ~570,000 years).
  if (t_s > 1.8e13) return fail(col, "time out of range");
  const uint64_t t = seconds_to_us(t_s);
  if (have_time_ && t < last_t_us_) {
    return fail(col, ("goes backwards (previous row t_s=" + std::to_string(us_to_seconds(last_t_us_)) +
                      ")").c_str());
  }
  t_us = t;
  return true;
}

void Table::accept_time(uint64_t t_us) {
  last_t_us_ = t_us;
  have_time_ = true;
}

LineBuilder& LineBuilder::time(uint64_t t_us) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, t_us / 1000000U);
  s_.append(buf, r.ptr);
  uint64_t frac = t_us % 1000000U;
  char digits[7];
  digits[0] = '.';
  for (int i = 6; i >= 1; --i) {
    digits[i] = static_cast<char>('0' + frac % 10U);
    frac /= 10U;
  }
  s_.append(digits, sizeof digits);
  return *this;
}

LineBuilder& LineBuilder::f32(float v) {
  if (!std::isfinite(v)) return *this;
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s_.append(buf, r.ptr);
  return *this;
}

LineBuilder& LineBuilder::f64(double v) {
  if (!std::isfinite(v)) return *this;
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s_.append(buf, r.ptr);
  return *this;
}

LineBuilder& LineBuilder::u64(uint64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s_.append(buf, r.ptr);
  return *this;
}

LineBuilder& LineBuilder::i64(int64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s_.append(buf, r.ptr);
  return *this;
}

bool LineBuilder::flush_to(std::FILE* f) {
  s_.push_back('\n');
  const bool good = std::fwrite(s_.data(), 1, s_.size(), f) == s_.size();
  s_.clear();
  return good;
}

std::string join(const Columns& cols, size_t num_optional) {
  std::string s;
  for (const char* c : cols.required) {
    if (!s.empty()) s += ',';
    s += c;
  }
  for (size_t i = 0; i < num_optional && i < cols.optional.size(); ++i) {
    s += ',';
    s += cols.optional[i];
  }
  return s;
}

}  // namespace uwbnav::dataset::csv
