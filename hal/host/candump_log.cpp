// candump -l log writer/reader and the logging CanBus decorator.
#include "hal/host/candump_log.hpp"

#include <cctype>
#include <cstdio>
#include <string>

namespace uwbnav::hal {
namespace {

constexpr char kHex[] = "0123456789ABCDEF";

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool parse_hex_u32(const std::string& s, uint32_t& out) {
  if (s.empty() || s.size() > 8) return false;
  uint32_t v = 0;
  for (char c : s) {
    const int h = hex_value(c);
    if (h < 0) return false;
    v = (v << 4) | static_cast<uint32_t>(h);
  }
  out = v;
  return true;
}

// Writes `v` as `digits` decimal digits, zero-padded (v < 10^digits); returns the end.
char* put_decimal(char* p, uint64_t v, int digits) {
  for (int i = digits - 1; i >= 0; --i) {
    p[i] = static_cast<char>('0' + v % 10U);
    v /= 10U;
  }
  return p + digits;
}

// Writes the low `digits` hex digits of `v` (upper case); returns the end.
char* put_hex(char* p, uint32_t v, int digits) {
  for (int i = digits - 1; i >= 0; --i) *p++ = kHex[(v >> (4 * i)) & 0xFU];
  return p;
}

}  // namespace

std::string format_candump_line(const CanFrame& frame, const std::string& ifname, uint64_t epoch_offset_us) {
  const uint64_t t = epoch_offset_us + frame.t_us;
  const uint64_t t_s = t / 1000000U;
  std::string line;
  line.reserve(48 + ifname.size() + 2 * 64);
  line += '(';
  if (t_s >= 10000000000ULL) {
    line += std::to_string(t_s);  // wider than the usual 10 digits (as %010 prints it)
  } else {
    char digits[10];
    line.append(digits, put_decimal(digits, t_s, 10));
  }
  char buf[32 + 2 * 64];  // ".uuuuuu) " + id + "##F" + up to 64 data bytes in hex
  char* p = buf;
  *p++ = '.';
  p = put_decimal(p, t % 1000000U, 6);
  *p++ = ')';
  *p++ = ' ';
  line.append(buf, p);
  line += ifname;
  p = buf;
  *p++ = ' ';
  if ((frame.flags & CanFrame::kFlagError) != 0) {
    p = put_hex(p, (frame.id & 0x1FFFFFFFU) | kCanErrFlag, 8);
  } else if ((frame.flags & CanFrame::kFlagExtended) != 0) {
    p = put_hex(p, frame.id & 0x1FFFFFFFU, 8);
  } else {
    p = put_hex(p, frame.id & 0x7FFU, 3);
  }
  *p++ = '#';
  const bool fd = (frame.flags & CanFrame::kFlagFd) != 0 && (frame.flags & CanFrame::kFlagError) == 0;
  const size_t len = frame.len > (fd ? 64U : 8U) ? (fd ? 64U : 8U) : frame.len;
  if (fd) {
    *p++ = '#';
    *p++ = kHex[(frame.flags & CanFrame::kFlagBrs) != 0 ? 1 : 0];
  }
  for (size_t i = 0; i < len; ++i) {
    *p++ = kHex[frame.data[i] >> 4];
    *p++ = kHex[frame.data[i] & 0x0F];
  }
  line.append(buf, p);
  return line;
}

Status parse_candump_line(const std::string& line, CanFrame& frame, std::string& ifname) {
  // "(sec.frac) ifname frame [T|R]"
  size_t p = 0;
  while (p < line.size() && std::isspace(static_cast<unsigned char>(line[p]))) ++p;
  if (p >= line.size() || line[p] != '(') return Status::kInvalidArgument;
  const size_t close = line.find(')', p);
  if (close == std::string::npos) return Status::kInvalidArgument;
  const std::string ts = line.substr(p + 1, close - p - 1);
  const size_t dot = ts.find('.');
  uint64_t sec = 0;
  uint64_t usec = 0;
  const std::string sec_s = dot == std::string::npos ? ts : ts.substr(0, dot);
  if (sec_s.empty()) return Status::kInvalidArgument;
  for (char c : sec_s) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return Status::kInvalidArgument;
    sec = sec * 10 + static_cast<uint64_t>(c - '0');
  }
  if (dot != std::string::npos) {
    const std::string frac = ts.substr(dot + 1);
    uint64_t scale = 100000;
    for (char c : frac) {
      if (!std::isdigit(static_cast<unsigned char>(c))) return Status::kInvalidArgument;
      usec += static_cast<uint64_t>(c - '0') * scale;
      scale /= 10;
    }
  }
  // Remaining whitespace-separated tokens: ifname, frame, optional direction.
  std::string tokens[3];
  size_t n = 0;
  size_t q = close + 1;
  while (q < line.size() && n < 3) {
    while (q < line.size() && std::isspace(static_cast<unsigned char>(line[q]))) ++q;
    const size_t start = q;
    while (q < line.size() && !std::isspace(static_cast<unsigned char>(line[q]))) ++q;
    if (q > start) tokens[n++] = line.substr(start, q - start);
  }
  if (n < 2) return Status::kInvalidArgument;
  const std::string& fs = tokens[1];
  const size_t hash = fs.find('#');
  if (hash == std::string::npos) return Status::kInvalidArgument;
  const std::string id_s = fs.substr(0, hash);
  uint32_t raw_id = 0;
  if (!parse_hex_u32(id_s, raw_id)) return Status::kInvalidArgument;

  CanFrame f;
  f.t_us = sec * 1000000U + usec;
  if (id_s.size() > 3) {
    if ((raw_id & kCanErrFlag) != 0) {
      f.flags |= CanFrame::kFlagError;
    } else {
      f.flags |= CanFrame::kFlagExtended;
    }
    f.id = raw_id & 0x1FFFFFFFU;
  } else {
    if (raw_id > 0x7FFU) return Status::kInvalidArgument;
    f.id = raw_id;
  }
  size_t d = hash + 1;
  size_t max_len = 8;
  if (d < fs.size() && fs[d] == '#') {
    if (d + 1 >= fs.size()) return Status::kInvalidArgument;
    const int fl = hex_value(fs[d + 1]);
    if (fl < 0) return Status::kInvalidArgument;
    f.flags |= CanFrame::kFlagFd;
    if ((fl & 0x1) != 0) f.flags |= CanFrame::kFlagBrs;
    d += 2;
    max_len = 64;
  } else if (d < fs.size() && (fs[d] == 'R' || fs[d] == 'r')) {
    return Status::kUnsupported;
  }
  size_t len = 0;
  while (d < fs.size()) {
    if (fs[d] == '_') break;  // classic len8_dlc suffix "_X": DLC code > 8, payload stays 8 bytes
    if (fs[d] == '.') {       // optional byte separator accepted by canplayer
      ++d;
      continue;
    }
    if (d + 1 >= fs.size()) return Status::kInvalidArgument;
    const int hi = hex_value(fs[d]);
    const int lo = hex_value(fs[d + 1]);
    if (hi < 0 || lo < 0 || len >= max_len) return Status::kInvalidArgument;
    f.data[len++] = static_cast<uint8_t>((hi << 4) | lo);
    d += 2;
  }
  f.len = static_cast<uint8_t>(len);
  frame = f;
  ifname = tokens[0];
  return Status::kOk;
}

CandumpLogWriter::~CandumpLogWriter() { ignore_status(close()); }

Status CandumpLogWriter::open(const std::string& path, const std::string& ifname, uint64_t epoch_offset_us) {
  ignore_status(close());
  f_ = std::fopen(path.c_str(), "w");
  if (f_ == nullptr) return Status::kIoError;
  ifname_ = ifname;
  epoch_offset_us_ = epoch_offset_us;
  lines_ = 0;
  return Status::kOk;
}

Status CandumpLogWriter::write(const CanFrame& frame) {
  if (f_ == nullptr) return Status::kNotInitialised;
  std::string line = format_candump_line(frame, ifname_, epoch_offset_us_);
  line += '\n';
  if (std::fwrite(line.data(), 1, line.size(), f_) != line.size()) return Status::kIoError;
  ++lines_;
  return Status::kOk;
}

Status CandumpLogWriter::close() {
  if (f_ == nullptr) return Status::kOk;
  const int rc = std::fclose(f_);
  f_ = nullptr;
  return rc == 0 ? Status::kOk : Status::kIoError;
}

CandumpLogReader::~CandumpLogReader() {
  if (f_ != nullptr) std::fclose(f_);
}

Status CandumpLogReader::open(const std::string& path) {
  if (f_ != nullptr) std::fclose(f_);
  f_ = std::fopen(path.c_str(), "r");
  skipped_ = 0;
  return f_ == nullptr ? Status::kIoError : Status::kOk;
}

Status CandumpLogReader::next(CanFrame& frame, std::string* ifname) {
  if (f_ == nullptr) return Status::kNotInitialised;
  std::string line;
  int c = 0;
  while (true) {
    line.clear();
    while ((c = std::fgetc(f_)) != EOF && c != '\n') line += static_cast<char>(c);
    if (line.empty() && c == EOF) return Status::kEmpty;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::string name;
    if (parse_candump_line(line, frame, name) == Status::kOk) {
      if (ifname != nullptr) *ifname = name;
      return Status::kOk;
    }
    ++skipped_;
  }
}

Status CanLogTee::send(const CanFrame& frame) {
  const Status s = inner_.send(frame);
  if (s == Status::kOk && log_.write(frame) != Status::kOk) ++log_errors_;
  return s;
}

Status CanLogTee::receive(CanFrame& out) {
  const Status s = inner_.receive(out);
  if (s == Status::kOk && log_rx_ && log_.write(out) != Status::kOk) ++log_errors_;
  return s;
}

}  // namespace uwbnav::hal
