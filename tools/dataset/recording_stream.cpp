// Streaming format v1 reader (see recording_stream.hpp): meta.ini, anchors and
// tags read whole, the time-series tables row by row with one row of look-ahead.
#include "tools/dataset/recording_stream.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <system_error>

#include "tools/dataset/tables.hpp"

namespace uwbnav::dataset {

namespace {

// UwbRange::anchor_id is uint16_t: uwb.csv accepts 0..65535; ids kFirstVehicleId..0xFFFE
// name a neighbour vehicle's tag (neighbours.csv), the reader passes them on like any id.
constexpr uint64_t kMaxAnchorId = 0xFFFF;
constexpr uint64_t kMaxTagId = 0xFF;       // UwbRange::tag_id is uint8_t
constexpr uint64_t kMaxNumSv = 0xFF;       // GnssFix::num_sv is uint8_t
constexpr double kMaxGnssLatencyS = 60.0;  // gnss.csv latency_s accepted up to [s]
constexpr double kMaxGnssLeverM = 100.0;   // meta.ini gnss_lever_m, per axis [m]
constexpr double kMaxNeighbourLatencyS = 60.0;  // neighbours.csv latency_s accepted up to [s]

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

// "x,y,z" or "x y z" (commas and/or blanks between three finite numbers).
bool parse_meta_vec3(const std::string& s, double max_abs, Vec3f& out) {
  double v[3] = {0, 0, 0};
  size_t n = 0;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ',' || s[i] == ' ' || s[i] == '\t')) ++i;
    if (i >= s.size()) break;
    size_t e = i;
    while (e < s.size() && s[e] != ',' && s[e] != ' ' && s[e] != '\t') ++e;
    if (n == 3 || !parse_meta_number(s.substr(i, e - i), v[n]) || std::fabs(v[n]) > max_abs) return false;
    ++n;
    i = e;
  }
  if (n != 3) return false;
  out = Vec3f{static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
  return true;
}

// meta.ini: "key = value" lines, '#' and ';' comments. Unusable lines and
// values are warned about and left out; the recording still loads.
Status read_meta(const std::string& dir, std::map<std::string, std::string>& meta, SiteConfig& site,
                 ReadReport& report) {
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
        site.platform = Platform::kGround;
      } else if (value == "air") {
        site.platform = Platform::kAir;
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
      site.gravity_mps2 = static_cast<float>(v);
    } else if (key == "gnss_lever_m") {
      if (!parse_meta_vec3(value, kMaxGnssLeverM, site.gnss_lever_body_m)) {
        csv::warn(report, "meta.ini", line_no,
                  "gnss_lever_m " + csv::quote(value.data(), value.size()) +
                      " is not three numbers x,y,z in [-100, 100] m; ignored");
        continue;
      }
    } else if (key == "uwb_sigma_m") {
      if (!parse_meta_number(value, v) || v <= 0.0 || v > 100.0) {
        csv::warn(report, "meta.ini", line_no,
                  "uwb_sigma_m " + csv::quote(value.data(), value.size()) + " is not in (0, 100]; ignored");
        continue;
      }
    }
    meta[key] = value;
  }
  return Status::kOk;
}

// Opens dir/file as a table: kOk with `table` set when present with a good
// header; kOk with `table` null when an optional file is absent or headerless.
Status open_table(const std::string& dir, const char* file, const csv::Columns& cols, bool required,
                  ReadReport& report, csv::LineReader& lines, std::unique_ptr<csv::Table>& table) {
  table.reset();
  const Status st = lines.open(dir + "/" + file);
  if (st == Status::kNotFound) {
    if (!required) return Status::kOk;
    report.error = std::string(file) + ": required file missing in " + dir + " (nor " + file +
                   ".gz; format v1 needs anchors.csv and uwb.csv; docs/dataset-format.md)";
    return st;
  }
  if (st != Status::kOk) {
    report.error = std::string(file) + ": cannot be read (" + lines.error() + ")";
    return st;
  }
  auto t = std::make_unique<csv::Table>(lines, file);
  std::string error;
  const Status hs = t->header(cols, error);
  if (!ok(lines.status())) {
    report.error = std::string(file) + ": cannot be read (" + lines.error() + ")";
    return lines.status();
  }
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
  table = std::move(t);
  return Status::kOk;
}

// Reads a whole small table through `fn(table, reason) -> bool` (anchors, tags).
template <typename RowFn>
Status read_small_table(const std::string& dir, const char* file, const csv::Columns& cols, bool required,
                        ReadReport& report, bool& present, RowFn fn) {
  csv::LineReader lines;
  std::unique_ptr<csv::Table> table;
  const Status st = open_table(dir, file, cols, required, report, lines, table);
  present = table != nullptr;
  if (!ok(st) || !present) return st;
  std::string reason;
  while (table->next_row()) {
    reason.clear();
    if (table->check_cell_count() && fn(*table, reason)) {
      ++report.rows_read;
    } else {
      ++report.rows_skipped;
      csv::warn(report, file, table->line(), reason.empty() ? table->reason() : reason);
    }
  }
  if (!ok(lines.status())) {
    report.error = std::string(file) + ": cannot be read (" + lines.error() + ")";
    return lines.status();
  }
  return Status::kOk;
}

}  // namespace

bool parse_row(csv::Table& t, UwbRow& row, std::string&) {
  row = UwbRow{};
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
  if (!t.parse_float_or_nan(5, row.range.fp_power_dbm) || !t.parse_float_or_nan(6, row.range.rx_power_dbm)) {
    return false;
  }
  row.range.anchor_id = static_cast<uint16_t>(anchor);
  row.range.tag_id = static_cast<uint8_t>(tag);
  t.accept_time(row.range.t_us);
  return true;
}

bool parse_row(csv::Table& t, ImuSample& s, std::string&) {
  s = ImuSample{};
  if (!t.parse_time(0, s.t_us) || !t.parse_float(1, s.accel_body_mps2.x) || !t.parse_float(2, s.accel_body_mps2.y) ||
      !t.parse_float(3, s.accel_body_mps2.z) || !t.parse_float(4, s.gyro_body_radps.x) ||
      !t.parse_float(5, s.gyro_body_radps.y) || !t.parse_float(6, s.gyro_body_radps.z)) {
    return false;
  }
  t.accept_time(s.t_us);
  return true;
}

bool parse_row(csv::Table& t, TruthRow& row, std::string& reason) {
  row = TruthRow{};
  if (!t.parse_time(0, row.t_us) || !t.parse_double(1, row.pos_nav_m[0]) || !t.parse_double(2, row.pos_nav_m[1]) ||
      !t.parse_double(3, row.pos_nav_m[2])) {
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
  return true;
}

bool parse_row(csv::Table& t, GnssFix& fix, std::string& reason) {
  fix = GnssFix{};
  if (!t.parse_time(0, fix.t_us)) return false;
  uint64_t quality = static_cast<uint64_t>(GnssFixType::kSingle);  // absent or empty: single
  if (!t.empty(7)) {
    if (!t.parse_uint(7, 0xFF, quality)) return false;
    if (quality != 0 && quality != 1 && quality != 2 && quality != 4 && quality != 5) {
      reason = "fix: unknown GGA quality code " + std::to_string(quality) +
               " (0 none, 1 single, 2 dgnss, 4 rtk fixed, 5 rtk float)";
      return false;
    }
  }
  fix.fix = static_cast<GnssFixType>(quality);
  fix.rx_t_us = fix.t_us;
  if (fix.fix == GnssFixType::kNone) {  // the receiver's "no fix": the other cells carry nothing
    t.accept_time(fix.t_us);
    return true;
  }
  float* const pos[3] = {&fix.pos_nav_m.x, &fix.pos_nav_m.y, &fix.pos_nav_m.z};
  float* const sigma[3] = {&fix.pos_sigma_m.x, &fix.pos_sigma_m.y, &fix.pos_sigma_m.z};
  for (size_t i = 0; i < 3; ++i) {
    if (!t.parse_float(1 + i, *pos[i])) return false;
  }
  for (size_t i = 0; i < 3; ++i) {
    if (!t.parse_float(4 + i, *sigma[i])) return false;
    if (!(*sigma[i] > 0.0F)) {
      reason = std::string(tables::kGnss.required[4 + i]) + ": must be > 0";
      return false;
    }
  }
  uint64_t num_sv = 0;
  if (!t.empty(8) && !t.parse_uint(8, kMaxNumSv, num_sv)) return false;
  fix.num_sv = static_cast<uint8_t>(num_sv);
  if (!t.empty(9)) {
    double latency_s = 0.0;
    if (!t.parse_double(9, latency_s)) return false;
    if (latency_s < 0.0) {
      reason = "latency_s: negative (the fix cannot arrive before its time of validity)";
      return false;
    }
    if (latency_s > kMaxGnssLatencyS) {
      reason = "latency_s: above 60 s";
      return false;
    }
    fix.rx_t_us = fix.t_us + seconds_to_us(latency_s);
  }
  size_t vel_cells = 0;
  for (size_t i = 10; i < 13; ++i) vel_cells += t.empty(i) ? 0U : 1U;
  if (vel_cells == 3) {
    if (!t.parse_float(10, fix.vel_nav_mps.x) || !t.parse_float(11, fix.vel_nav_mps.y) ||
        !t.parse_float(12, fix.vel_nav_mps.z)) {
      return false;
    }
  } else if (vel_cells != 0) {
    reason = "velocity partly empty (give all of vx_mps,vy_mps,vz_mps or none)";
    return false;
  }
  if (!t.parse_float_or_nan(13, fix.vel_sigma_mps)) return false;
  if (std::isfinite(fix.vel_sigma_mps) && !(fix.vel_sigma_mps > 0.0F)) {
    reason = "sv_mps: must be > 0";
    return false;
  }
  t.accept_time(fix.t_us);
  return true;
}

bool parse_row(csv::Table& t, NeighbourState& ns, std::string& reason) {
  ns = NeighbourState{};
  uint64_t id = 0;
  if (!t.parse_time(0, ns.t_us) || !t.parse_uint(1, kNoVehicleId - 1U, id)) return false;
  if (!is_vehicle_id(static_cast<uint16_t>(id))) {
    reason = "vehicle_id: " + std::to_string(id) + " is not a vehicle id (" + std::to_string(kFirstVehicleId) + ".." +
             std::to_string(kNoVehicleId - 1U) + ")";
    return false;
  }
  ns.vehicle_id = static_cast<uint16_t>(id);
  ns.rx_t_us = ns.t_us;
  if (!t.parse_float(2, ns.pos_nav_m.x) || !t.parse_float(3, ns.pos_nav_m.y) || !t.parse_float(4, ns.pos_nav_m.z)) {
    return false;
  }
  for (size_t i = 0; i < 6; ++i) {
    if (!t.parse_float(5 + i, ns.cov_pos_m2[i])) return false;
  }
  // Positive definite: positive diagonal, positive 2x2 principal minors and determinant.
  double c[6];
  for (size_t i = 0; i < 6; ++i) c[i] = static_cast<double>(ns.cov_pos_m2[i]);
  const double xx = c[0], xy = c[1], xz = c[2], yy = c[3], yz = c[4], zz = c[5];
  for (size_t i : {size_t{0}, size_t{3}, size_t{5}}) {
    if (!(c[i] > 0.0)) {
      reason = std::string(tables::kNeighbours.required[5 + i]) + ": must be > 0 (a variance)";
      return false;
    }
  }
  const double det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  if (!(xx * yy - xy * xy > 0.0) || !(xx * zz - xz * xz > 0.0) || !(yy * zz - yz * yz > 0.0) || !(det > 0.0)) {
    reason = "covariance not positive definite (a 2x2 minor or the determinant <= 0)";
    return false;
  }
  if (!t.empty(11)) {
    double latency_s = 0.0;
    if (!t.parse_double(11, latency_s)) return false;
    if (latency_s < 0.0) {
      reason = "latency_s: negative (the state cannot arrive before its time of validity)";
      return false;
    }
    if (latency_s > kMaxNeighbourLatencyS) {
      reason = "latency_s: above 60 s";
      return false;
    }
    ns.rx_t_us = ns.t_us + seconds_to_us(latency_s);
  }
  size_t vel_cells = 0;
  for (size_t i = 12; i < 15; ++i) vel_cells += t.empty(i) ? 0U : 1U;
  if (vel_cells == 3) {
    if (!t.parse_float(12, ns.vel_nav_mps.x) || !t.parse_float(13, ns.vel_nav_mps.y) ||
        !t.parse_float(14, ns.vel_nav_mps.z)) {
      return false;
    }
  } else if (vel_cells != 0) {
    reason = "velocity partly empty (give all of vx_mps,vy_mps,vz_mps or none)";
    return false;
  }
  uint64_t coop = 0;
  if (!t.empty(15) && !t.parse_uint(15, 1, coop)) return false;
  ns.cooperative = coop != 0;
  return true;
}

template <typename Row>
Status RowStream<Row>::open(const std::string& dir, const char* file, const csv::Columns& cols, bool required,
                            ReadReport& report) {
  report_ = &report;
  file_ = file;
  have_ = false;
  delivered_ = 0;
  last_t_us_ = 0;
  const Status st = open_table(dir, file, cols, required, report, lines_, table_);
  if (!ok(st) || table_ == nullptr) return st;
  advance();
  if (!ok(status())) {
    report.error = error();
    return status();
  }
  return Status::kOk;
}

template <typename Row>
void RowStream<Row>::advance() {
  have_ = false;
  if (table_ == nullptr) return;
  while (table_->next_row()) {
    reason_.clear();
    if (table_->check_cell_count() && parse_row(*table_, row_, reason_)) {
      ++report_->rows_read;
      have_ = true;
      return;
    }
    ++report_->rows_skipped;
    csv::warn(*report_, file_, table_->line(), reason_.empty() ? table_->reason() : reason_);
  }
}

template <typename Row>
bool RowStream<Row>::next(Row& out) {
  if (!have_) return false;
  out = row_;
  last_t_us_ = row_time_us(row_);
  ++delivered_;
  advance();
  return true;
}

template <typename Row>
std::string RowStream<Row>::error() const {
  if (ok(status())) return std::string();
  return std::string(file_) + ": cannot be read (" + lines_.error() + ")";
}

template class RowStream<UwbRow>;
template class RowStream<ImuSample>;
template class RowStream<TruthRow>;

Status read_site(const std::string& dir, std::map<std::string, std::string>& meta, SiteConfig& site,
                 ReadReport& report) {
  struct stat dir_stat {};
  if (::stat(dir.c_str(), &dir_stat) != 0) {
    report.error = dir + ": no such directory (a recording is a directory of format v1 files)";
    return Status::kNotFound;
  }
  if (!S_ISDIR(dir_stat.st_mode)) {
    report.error = dir + ": not a directory (a recording is a directory of format v1 files)";
    return Status::kInvalidArgument;
  }
  Status st = read_meta(dir, meta, site, report);
  if (st != Status::kOk) return st;

  bool present = false;
  st = read_small_table(dir, "anchors.csv", tables::kAnchors, true, report, present,
                        [&](csv::Table& t, std::string& reason) {
                          uint64_t id = 0;
                          Vec3f p;
                          if (!t.parse_uint(0, kMaxAnchorId, id) || !t.parse_float(1, p.x) ||
                              !t.parse_float(2, p.y) || !t.parse_float(3, p.z)) {
                            return false;
                          }
                          const Status add = site.add_anchor(static_cast<uint16_t>(id), p);
                          if (add == Status::kFull) {
                            reason = "more than " + std::to_string(kMaxAnchors) + " anchors; anchor " +
                                     std::to_string(id) + " ignored";
                          } else if (add != Status::kOk) {
                            reason = "duplicate anchor_id " + std::to_string(id);
                          }
                          return add == Status::kOk;
                        });
  if (st != Status::kOk) return st;
  if (site.num_anchors == 0) {
    report.error = "anchors.csv: no usable anchor row";
    return Status::kInvalidArgument;
  }

  st = read_small_table(dir, "tags.csv", tables::kTags, false, report, present,
                        [&](csv::Table& t, std::string& reason) {
                          uint64_t id = 0;
                          Vec3f lever;
                          if (!t.parse_uint(0, kMaxTagId, id) || !t.parse_float(1, lever.x) ||
                              !t.parse_float(2, lever.y) || !t.parse_float(3, lever.z)) {
                            return false;
                          }
                          const Status add = site.add_tag(static_cast<uint8_t>(id), lever);
                          if (add == Status::kFull) {
                            reason = "more than " + std::to_string(kMaxTags) + " tags; tag " +
                                     std::to_string(id) + " ignored";
                          } else if (add != Status::kOk) {
                            reason = "duplicate tag_id " + std::to_string(id);
                          }
                          return add == Status::kOk;
                        });
  if (st != Status::kOk) return st;
  if (site.num_tags == 0) {
    if (present) csv::warn(report, "tags.csv", 0, "no usable tag row; using tag 0 at the body origin");
    ignore_status(site.add_tag(0, Vec3f{}));
  }
  return Status::kOk;
}

Status read_gnss(const std::string& dir, std::vector<GnssFix>& out, ReadReport& report) {
  out.clear();
  bool present = false;
  const Status st = read_small_table(dir, "gnss.csv", tables::kGnss, false, report, present,
                                     [&](csv::Table& t, std::string& reason) {
                                       GnssFix fix;
                                       if (!parse_row(t, fix, reason)) return false;
                                       if (fix.fix != GnssFixType::kNone) out.push_back(fix);
                                       return true;
                                     });
  // The file is in time-of-validity order; consumers take fixes as they arrive.
  std::stable_sort(out.begin(), out.end(),
                   [](const GnssFix& a, const GnssFix& b) { return a.rx_t_us < b.rx_t_us; });
  return st;
}

Status read_neighbours(const std::string& dir, std::vector<NeighbourState>& out, ReadReport& report) {
  out.clear();
  bool present = false;
  std::map<uint16_t, uint64_t> last_t_us;  // per vehicle: time of its last good row
  const Status st = read_small_table(dir, "neighbours.csv", tables::kNeighbours, false, report, present,
                                     [&](csv::Table& t, std::string& reason) {
                                       NeighbourState ns;
                                       if (!parse_row(t, ns, reason)) return false;
                                       const auto it = last_t_us.find(ns.vehicle_id);
                                       if (it != last_t_us.end() && ns.t_us < it->second) {
                                         reason = "t_s: goes backwards for vehicle " + std::to_string(ns.vehicle_id) +
                                                  " (its previous row t_s=" +
                                                  std::to_string(us_to_seconds(it->second)) + ")";
                                         return false;
                                       }
                                       last_t_us[ns.vehicle_id] = ns.t_us;
                                       out.push_back(ns);
                                       return true;
                                     });
  // Consumers take the states as they arrive.
  std::stable_sort(out.begin(), out.end(),
                   [](const NeighbourState& a, const NeighbourState& b) { return a.rx_t_us < b.rx_t_us; });
  return st;
}

Status RecordingStream::open(const std::string& directory, ReadReport& report, bool with_truth) {
  dir = directory;
  meta.clear();
  site = SiteConfig{};
  gnss.clear();
  neighbours.clear();
  Status st = read_site(dir, meta, site, report);
  if (!ok(st)) return st;
  st = uwb.open(dir, "uwb.csv", tables::kUwb, true, report);
  if (!ok(st)) return st;
  st = imu.open(dir, "imu.csv", tables::kImu, false, report);
  if (!ok(st)) return st;
  site.has_imu = imu.peek() != nullptr;
  st = read_gnss(dir, gnss, report);
  if (!ok(st)) return st;
  st = read_neighbours(dir, neighbours, report);
  if (!ok(st)) return st;
  if (with_truth) st = truth.open(dir, "truth.csv", tables::kTruth, false, report);
  return st;
}

std::string RecordingStream::read_error() const {
  if (!ok(uwb.status())) return uwb.error();
  if (!ok(imu.status())) return imu.error();
  if (!ok(truth.status())) return truth.error();
  return std::string();
}

}  // namespace uwbnav::dataset
