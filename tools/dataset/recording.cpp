// Format v1 recording reader (docs/dataset-format.md): meta.ini, anchors,
// tags, uwb, imu and truth tables into a Recording, skipping bad rows with a
// "file:line: reason" warning each.
#include "tools/dataset/recording.hpp"

#include <sys/stat.h>

#include <charconv>
#include <cmath>
#include <system_error>

#include "tools/dataset/csv.hpp"
#include "tools/dataset/tables.hpp"
#include "tools/dataset/text_source.hpp"

namespace uwbnav::dataset {

namespace {

constexpr uint64_t kMaxAnchorId = 0xFFFF;  // UwbRange::anchor_id is uint16_t
constexpr uint64_t kMaxTagId = 0xFF;       // UwbRange::tag_id is uint8_t

std::string trimmed(const std::string& s) {
  size_t b = 0;
  size_t e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  return s.substr(b, e - b);
}

bool parse_meta_number(const std::string& s, double& out) {
  const char* b = s.data();
  const char* e = b + s.size();
  if (b < e && *b == '+') ++b;
  double v = 0.0;
  const auto r = std::from_chars(b, e, v, std::chars_format::general);
  if (r.ec != std::errc() || r.ptr != e || !std::isfinite(v)) return false;
  out = v;
  return true;
}

// meta.ini: "key = value" lines, '#' and ';' comments. Unusable lines and
// values are warned about and left out; the recording still loads.
Status read_meta(const std::string& dir, Recording& out, ReadReport& report) {
  std::string text;
  const Status st = csv::read_file(dir + "/meta.ini", text);
  if (st == Status::kNotFound) return Status::kOk;
  if (st != Status::kOk) {
    report.error = "meta.ini: cannot be read";
    return st;
  }
  size_t line_no = 0;
  size_t pos = 0;
  std::string line;
  while (csv::next_line(text, pos, line_no, line)) {
    line = trimmed(line);
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    const size_t eq = line.find('=');
    if (eq == std::string::npos) {
      csv::warn(report, "meta.ini", line_no, "not a 'key = value' line " + csv::quote(line.data(), line.size()));
      continue;
    }
    const std::string key = trimmed(line.substr(0, eq));
    const std::string value = trimmed(line.substr(eq + 1));
    if (key.empty()) {
      csv::warn(report, "meta.ini", line_no, "empty key");
      continue;
    }
    double v = 0.0;
    if (key == "platform") {
      if (value == "ground") {
        out.site.platform = Platform::kGround;
      } else if (value == "air") {
        out.site.platform = Platform::kAir;
      } else {
        csv::warn(report, "meta.ini", line_no,
                  "platform " + csv::quote(value.data(), value.size()) + " is neither ground nor air; ignored");
        continue;
      }
    } else if (key == "gravity_mps2") {
      if (!parse_meta_number(value, v) || v <= 0.0 || v > 100.0) {
        csv::warn(report, "meta.ini", line_no,
                  "gravity_mps2 " + csv::quote(value.data(), value.size()) + " is not in (0, 100]; ignored");
        continue;
      }
      out.site.gravity_mps2 = static_cast<float>(v);
    } else if (key == "uwb_sigma_m") {
      if (!parse_meta_number(value, v) || v <= 0.0 || v > 100.0) {
        csv::warn(report, "meta.ini", line_no,
                  "uwb_sigma_m " + csv::quote(value.data(), value.size()) + " is not in (0, 100]; ignored");
        continue;
      }
    }
    out.meta[key] = value;
  }
  return Status::kOk;
}

// Reads one table of `dir` row by row through `fn(table, reason) -> bool`.
// `present` tells whether the file existed with a header.
template <typename RowFn>
Status read_table(const std::string& dir, const char* file, const csv::Columns& cols, bool required,
                  ReadReport& report, bool& present, RowFn fn) {
  present = false;
  std::string text;
  std::string why;
  const Status st = read_text_file(dir + "/" + file, text, &why);
  if (st == Status::kNotFound) {
    if (!required) return Status::kOk;
    report.error = std::string(file) + ": required file missing in " + dir + " (nor " + file +
                   ".gz; format v1 needs anchors.csv and uwb.csv; docs/dataset-format.md)";
    return st;
  }
  if (st != Status::kOk) {
    report.error = std::string(file) + ": cannot be read (" + why + ")";
    return st;
  }
  csv::Table table(text, file);
  std::string error;
  const Status hs = table.header(cols, error);
  if (hs == Status::kEmpty) {
    if (required) {
      report.error = std::string(file) + ": no header line (file empty or only comments)";
      return Status::kInvalidArgument;
    }
    csv::warn(report, file, 0, "no header line (file empty or only comments); file ignored");
    return Status::kOk;
  }
  if (hs != Status::kOk) {
    report.error = error;
    return hs;
  }
  present = true;
  std::string reason;
  while (table.next_row()) {
    reason.clear();
    if (table.check_cell_count() && fn(table, reason)) {
      ++report.rows_read;
    } else {
      ++report.rows_skipped;
      csv::warn(report, file, table.line(), reason.empty() ? table.reason() : reason);
    }
  }
  return Status::kOk;
}

}  // namespace

std::string Recording::name() const {
  const auto it = meta.find("name");
  if (it != meta.end() && !it->second.empty()) return it->second;
  std::string d = dir;
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  const size_t slash = d.find_last_of('/');
  return slash == std::string::npos ? d : d.substr(slash + 1);
}

uint64_t seconds_to_us(double t_s) {
  if (!(t_s > 0.0)) return 0;  // also NaN
  if (t_s > 1.8e13) return static_cast<uint64_t>(1.8e19);
  return static_cast<uint64_t>(std::llround(t_s * 1e6));
}

double us_to_seconds(uint64_t t_us) { return static_cast<double>(t_us) / 1e6; }

void print_warnings(const ReadReport& report, std::FILE* out) {
  for (const auto& w : report.warnings) std::fprintf(out, "warning: %s\n", w.c_str());
  if (report.warnings_dropped > 0) {
    std::fprintf(out, "warning: ... %zu more warnings not shown\n", report.warnings_dropped);
  }
}

Status read_recording(const std::string& dir, Recording& out, ReadReport& report) {
  out = Recording{};
  out.dir = dir;
  struct stat dir_stat {};
  if (::stat(dir.c_str(), &dir_stat) != 0) {
    report.error = dir + ": no such directory (a recording is a directory of format v1 files)";
    return Status::kNotFound;
  }
  if (!S_ISDIR(dir_stat.st_mode)) {
    report.error = dir + ": not a directory (a recording is a directory of format v1 files)";
    return Status::kInvalidArgument;
  }
  Status st = read_meta(dir, out, report);
  if (st != Status::kOk) return st;

  bool present = false;
  st = read_table(dir, "anchors.csv", tables::kAnchors, true, report, present,
                  [&](csv::Table& t, std::string& reason) {
                    uint64_t id = 0;
                    Vec3f p;
                    if (!t.parse_uint(0, kMaxAnchorId, id) || !t.parse_float(1, p.x) ||
                        !t.parse_float(2, p.y) || !t.parse_float(3, p.z)) {
                      return false;
                    }
                    const Status add = out.site.add_anchor(static_cast<uint16_t>(id), p);
                    if (add == Status::kFull) {
                      reason = "more than " + std::to_string(kMaxAnchors) + " anchors; anchor " +
                               std::to_string(id) + " ignored";
                    } else if (add != Status::kOk) {
                      reason = "duplicate anchor_id " + std::to_string(id);
                    }
                    return add == Status::kOk;
                  });
  if (st != Status::kOk) return st;
  if (out.site.num_anchors == 0) {
    report.error = "anchors.csv: no usable anchor row";
    return Status::kInvalidArgument;
  }

  st = read_table(dir, "tags.csv", tables::kTags, false, report, present,
                  [&](csv::Table& t, std::string& reason) {
                    uint64_t id = 0;
                    Vec3f lever;
                    if (!t.parse_uint(0, kMaxTagId, id) || !t.parse_float(1, lever.x) ||
                        !t.parse_float(2, lever.y) || !t.parse_float(3, lever.z)) {
                      return false;
                    }
                    const Status add = out.site.add_tag(static_cast<uint8_t>(id), lever);
                    if (add == Status::kFull) {
                      reason = "more than " + std::to_string(kMaxTags) + " tags; tag " +
                               std::to_string(id) + " ignored";
                    } else if (add != Status::kOk) {
                      reason = "duplicate tag_id " + std::to_string(id);
                    }
                    return add == Status::kOk;
                  });
  if (st != Status::kOk) return st;
  if (out.site.num_tags == 0) {
    if (present) csv::warn(report, "tags.csv", 0, "no usable tag row; using tag 0 at the body origin");
    ignore_status(out.site.add_tag(0, Vec3f{}));
  }

  st = read_table(dir, "uwb.csv", tables::kUwb, true, report, present,
                  [&](csv::Table& t, std::string&) {
                    UwbRow row;
                    uint64_t anchor = 0;
                    uint64_t tag = 0;
                    uint64_t nlos = 0;
                    if (!t.parse_time(0, row.range.t_us) || !t.parse_uint(1, kMaxAnchorId, anchor) ||
                        !t.parse_float(2, row.range.range_m)) {
                      return false;
                    }
                    if (!t.empty(3) && !t.parse_uint(3, kMaxTagId, tag)) return false;
                    if (!t.empty(4)) {
                      if (!t.parse_uint(4, 1, nlos)) return false;
                      row.nlos_label = static_cast<int8_t>(nlos);
                    }
                    if (!t.parse_float_or_nan(5, row.range.fp_power_dbm) ||
                        !t.parse_float_or_nan(6, row.range.rx_power_dbm)) {
                      return false;
                    }
                    row.range.anchor_id = static_cast<uint16_t>(anchor);
                    row.range.tag_id = static_cast<uint8_t>(tag);
                    t.accept_time(row.range.t_us);
                    out.uwb.push_back(row);
                    return true;
                  });
  if (st != Status::kOk) return st;

  st = read_table(dir, "imu.csv", tables::kImu, false, report, present,
                  [&](csv::Table& t, std::string&) {
                    ImuSample s;
                    if (!t.parse_time(0, s.t_us) || !t.parse_float(1, s.accel_body_mps2.x) ||
                        !t.parse_float(2, s.accel_body_mps2.y) || !t.parse_float(3, s.accel_body_mps2.z) ||
                        !t.parse_float(4, s.gyro_body_radps.x) || !t.parse_float(5, s.gyro_body_radps.y) ||
                        !t.parse_float(6, s.gyro_body_radps.z)) {
                      return false;
                    }
                    t.accept_time(s.t_us);
                    out.imu.push_back(s);
                    return true;
                  });
  if (st != Status::kOk) return st;
  out.site.has_imu = !out.imu.empty();

  st = read_table(dir, "truth.csv", tables::kTruth, false, report, present,
                  [&](csv::Table& t, std::string& reason) {
                    TruthRow row;
                    if (!t.parse_time(0, row.t_us) || !t.parse_double(1, row.pos_nav_m[0]) ||
                        !t.parse_double(2, row.pos_nav_m[1]) || !t.parse_double(3, row.pos_nav_m[2])) {
                      return false;
                    }
                    size_t q_cells = 0;
                    for (size_t i = 4; i < 8; ++i) q_cells += t.empty(i) ? 0U : 1U;
                    if (q_cells == 4) {
                      for (size_t i = 0; i < 4; ++i) {
                        if (!t.parse_double(4 + i, row.q_nav_body[i])) return false;
                      }
                      row.has_attitude = true;
                    } else if (q_cells != 0) {
                      reason = "quaternion partly empty (give all of qw,qx,qy,qz or none)";
                      return false;
                    }
                    t.accept_time(row.t_us);
                    out.truth.push_back(row);
                    return true;
                  });
  return st;
}

std::vector<std::string> streams_ended_early(const Recording& rec) {
  std::vector<std::string> lines;
  if (rec.imu.empty() || rec.uwb.empty()) return lines;
  const uint64_t imu_end = rec.imu.back().t_us;
  const uint64_t uwb_end = rec.uwb.back().range.t_us;
  auto line = [&](const char* file, uint64_t end, const char* other, uint64_t other_end) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s: ends at t=%.3f s, %.3f s before %s (last %.3f s): input stream ended early",
                  file, us_to_seconds(end), us_to_seconds(other_end - end), other, us_to_seconds(other_end));
    lines.emplace_back(buf);
  };
  if (imu_end + kStreamEndToleranceUs < uwb_end) line("imu.csv", imu_end, "uwb.csv", uwb_end);
  if (uwb_end + kStreamEndToleranceUs < imu_end) line("uwb.csv", uwb_end, "imu.csv", imu_end);
  return lines;
}

}  // namespace uwbnav::dataset
