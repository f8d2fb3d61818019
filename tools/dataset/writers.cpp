// Format v1 writers (recording directory incl. the gnss.csv and neighbours.csv extensions,
// estimates.csv, ranges.csv) and the readers of the replay outputs (docs/dataset-format.md).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <system_error>

#include "tools/dataset/csv.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/dataset/tables.hpp"

namespace uwbnav::dataset {

namespace {

constexpr size_t kWriteBuffer = 1 << 16;  // stdio buffer per written file [bytes]

std::FILE* open_for_write(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f != nullptr) std::setvbuf(f, nullptr, _IOFBF, kWriteBuffer);
  return f;
}

// Closes `f` and folds any earlier write error into the status.
Status finish(std::FILE* f, bool good) {
  const bool closed = std::fclose(f) == 0;
  return good && closed ? Status::kOk : Status::kIoError;
}

// Writes one table: header with `num_optional` optional columns, then `rows`
// lines produced by `fill(i, line)`.
template <typename Fill>
Status write_table(const std::string& path, const csv::Columns& cols, size_t num_optional, size_t rows,
                   Fill fill) {
  std::FILE* f = open_for_write(path);
  if (f == nullptr) return Status::kIoError;
  csv::LineBuilder line;
  line.text(csv::join(cols, num_optional).c_str());
  bool good = line.flush_to(f);
  for (size_t i = 0; good && i < rows; ++i) {
    fill(i, line);
    good = line.flush_to(f);
  }
  return finish(f, good);
}

// One line of meta.ini; newlines in values would break the format.
std::string meta_line(const std::string& key, const std::string& value) {
  std::string v = value;
  for (char& c : v) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return key + " = " + v + "\n";
}

// Shortest text that reads back to the same float.
std::string float_text(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

Status write_meta(const std::string& path, const Recording& rec) {
  std::FILE* f = open_for_write(path);
  if (f == nullptr) return Status::kIoError;
  std::string text = "# format v1 recording (docs/dataset-format.md)\n";
  for (const auto& kv : rec.meta) {
    if (kv.first == "platform" || kv.first == "gravity_mps2" || kv.first == "gnss_lever_m") continue;
    text += meta_line(kv.first, kv.second);
  }
  // The site configuration is authoritative for the keys it carries.
  text += meta_line("platform", rec.site.platform == Platform::kAir ? "air" : "ground");
  text += meta_line("gravity_mps2", float_text(rec.site.gravity_mps2));
  const Vec3f& lever = rec.site.gnss_lever_body_m;
  if (!rec.gnss.empty() || lever.x != 0.0F || lever.y != 0.0F || lever.z != 0.0F) {
    text += meta_line("gnss_lever_m", float_text(lever.x) + "," + float_text(lever.y) + "," + float_text(lever.z));
  }
  const bool good = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  return finish(f, good);
}

// Removes an optional file left over from an earlier recording in `dir`.
void remove_stale(const std::string& path) {
  std::error_code ec;
  std::filesystem::remove(path, ec);
}

bool has_velocity(const GnssFix& f) {
  return std::isfinite(f.vel_nav_mps.x) && std::isfinite(f.vel_nav_mps.y) && std::isfinite(f.vel_nav_mps.z);
}

// gnss.csv in time-of-validity order (the file's order; `fixes` are in arrival
// order), optional columns up to the last one any fix has a value for.
Status write_gnss(const std::string& path, const std::vector<GnssFix>& fixes) {
  std::vector<const GnssFix*> rows;
  rows.reserve(fixes.size());
  size_t optional = 0;
  for (const GnssFix& f : fixes) {
    rows.push_back(&f);
    if (f.fix != GnssFixType::kSingle) optional = std::max<size_t>(optional, 1);
    if (f.num_sv != 0) optional = std::max<size_t>(optional, 2);
    if (f.rx_t_us != f.t_us) optional = std::max<size_t>(optional, 3);
    if (has_velocity(f)) optional = std::max<size_t>(optional, 6);
    if (std::isfinite(f.vel_sigma_mps)) optional = 7;
  }
  std::stable_sort(rows.begin(), rows.end(), [](const GnssFix* a, const GnssFix* b) { return a->t_us < b->t_us; });
  return write_table(path, tables::kGnss, optional, rows.size(), [&](size_t i, csv::LineBuilder& l) {
    const GnssFix& f = *rows[i];
    l.time(f.t_us).sep().f32(f.pos_nav_m.x).sep().f32(f.pos_nav_m.y).sep().f32(f.pos_nav_m.z);
    l.sep().f32(f.pos_sigma_m.x).sep().f32(f.pos_sigma_m.y).sep().f32(f.pos_sigma_m.z);
    if (optional >= 1) l.sep().u64(static_cast<uint64_t>(f.fix));
    if (optional >= 2) l.sep().u64(f.num_sv);
    if (optional >= 3) l.sep().time(f.rx_t_us >= f.t_us ? f.rx_t_us - f.t_us : 0);  // rx before t: written as 0
    if (optional >= 6 && has_velocity(f)) {
      l.sep().f32(f.vel_nav_mps.x).sep().f32(f.vel_nav_mps.y).sep().f32(f.vel_nav_mps.z);
    } else if (optional >= 6) {
      l.sep().sep().sep();  // not reported (all three empty: the reader refuses a partial velocity)
    }
    if (optional >= 7) l.sep().f32(f.vel_sigma_mps);
  });
}

bool has_velocity(const NeighbourState& n) {
  return std::isfinite(n.vel_nav_mps.x) && std::isfinite(n.vel_nav_mps.y) && std::isfinite(n.vel_nav_mps.z);
}

// neighbours.csv in time-of-validity order (`states` are in arrival order),
// optional columns up to the last one any state has a value for.
Status write_neighbours(const std::string& path, const std::vector<NeighbourState>& states) {
  std::vector<const NeighbourState*> rows;
  rows.reserve(states.size());
  size_t optional = 0;
  for (const NeighbourState& n : states) {
    rows.push_back(&n);
    if (n.rx_t_us != n.t_us) optional = std::max<size_t>(optional, 1);
    if (has_velocity(n)) optional = std::max<size_t>(optional, 4);
    if (n.cooperative) optional = 5;
  }
  std::stable_sort(rows.begin(), rows.end(),
                   [](const NeighbourState* a, const NeighbourState* b) { return a->t_us < b->t_us; });
  return write_table(path, tables::kNeighbours, optional, rows.size(), [&](size_t i, csv::LineBuilder& l) {
    const NeighbourState& n = *rows[i];
    l.time(n.t_us).sep().u64(n.vehicle_id);
    l.sep().f32(n.pos_nav_m.x).sep().f32(n.pos_nav_m.y).sep().f32(n.pos_nav_m.z);
    for (float c : n.cov_pos_m2) l.sep().f32(c);
    if (optional >= 1) l.sep().time(n.rx_t_us >= n.t_us ? n.rx_t_us - n.t_us : 0);  // rx before t: written as 0
    if (optional >= 4 && has_velocity(n)) {
      l.sep().f32(n.vel_nav_mps.x).sep().f32(n.vel_nav_mps.y).sep().f32(n.vel_nav_mps.z);
    } else if (optional >= 4) {
      l.sep().sep().sep();  // not reported (all three empty: the reader refuses a partial velocity)
    }
    if (optional >= 5) l.sep().u64(n.cooperative ? 1U : 0U);
  });
}

template <typename Row, typename RowFn>
Status read_output(const std::string& path, const csv::Columns& cols, std::vector<Row>& out,
                   ReadReport& report, RowFn fn) {
  out.clear();
  const std::string name = std::filesystem::path(path).filename().string();
  std::string text;
  const Status st = csv::read_file(path, text);
  if (st != Status::kOk) {
    report.error = path + (st == Status::kNotFound ? ": missing" : ": cannot be read");
    return st;
  }
  csv::Table table(text, name);
  std::string error;
  const Status hs = table.header(cols, error);
  if (hs == Status::kEmpty) {
    report.error = name + ": no header line (file empty or only comments)";
    return Status::kInvalidArgument;
  }
  if (hs != Status::kOk) {
    report.error = error;
    return hs;
  }
  Row row;
  while (table.next_row()) {
    row = Row{};
    if (table.check_cell_count() && fn(table, row)) {
      ++report.rows_read;
      out.push_back(row);
    } else {
      ++report.rows_skipped;
      csv::warn(report, name, table.line(), table.reason());
    }
  }
  return Status::kOk;
}

bool parse_double_or_nan(csv::Table& t, size_t col, double& out) {
  if (t.empty(col)) {
    out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  return t.parse_double(col, out);
}

}  // namespace

Status write_recording(const std::string& dir, const Recording& rec) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (!std::filesystem::is_directory(dir, ec)) return Status::kIoError;
  const SiteConfig& site = rec.site;

  Status st = write_table(dir + "/anchors.csv", tables::kAnchors, 0, site.num_anchors,
                          [&](size_t i, csv::LineBuilder& l) {
                            const Anchor& a = site.anchors[i];
                            l.u64(a.id).sep().f32(a.pos_nav_m.x).sep().f32(a.pos_nav_m.y).sep().f32(
                                a.pos_nav_m.z);
                          });
  if (st != Status::kOk) return st;

  if (site.num_tags > 0) {
    st = write_table(dir + "/tags.csv", tables::kTags, 0, site.num_tags, [&](size_t i, csv::LineBuilder& l) {
      const Tag& t = site.tags[i];
      l.u64(t.id).sep().f32(t.lever_body_m.x).sep().f32(t.lever_body_m.y).sep().f32(t.lever_body_m.z);
    });
    if (st != Status::kOk) return st;
  } else {
    remove_stale(dir + "/tags.csv");
  }

  // Optional uwb columns: up to the last one any row has a value for.
  size_t uwb_optional = 0;
  for (const UwbRow& r : rec.uwb) {
    if (r.range.tag_id != 0) uwb_optional = std::max<size_t>(uwb_optional, 1);
    if (r.nlos_label >= 0) uwb_optional = std::max<size_t>(uwb_optional, 2);
    if (std::isfinite(r.range.fp_power_dbm)) uwb_optional = std::max<size_t>(uwb_optional, 3);
    if (std::isfinite(r.range.rx_power_dbm)) uwb_optional = 4;
  }
  st = write_table(dir + "/uwb.csv", tables::kUwb, uwb_optional, rec.uwb.size(),
                   [&](size_t i, csv::LineBuilder& l) {
                     const UwbRow& r = rec.uwb[i];
                     l.time(r.range.t_us).sep().u64(r.range.anchor_id).sep().f32(r.range.range_m);
                     if (uwb_optional >= 1) l.sep().u64(r.range.tag_id);
                     if (uwb_optional >= 2) {
                       l.sep();
                       if (r.nlos_label >= 0) l.i64(r.nlos_label);
                     }
                     if (uwb_optional >= 3) l.sep().f32(r.range.fp_power_dbm);
                     if (uwb_optional >= 4) l.sep().f32(r.range.rx_power_dbm);
                   });
  if (st != Status::kOk) return st;

  if (!rec.imu.empty()) {
    st = write_table(dir + "/imu.csv", tables::kImu, 0, rec.imu.size(), [&](size_t i, csv::LineBuilder& l) {
      const ImuSample& s = rec.imu[i];
      l.time(s.t_us).sep().f32(s.accel_body_mps2.x).sep().f32(s.accel_body_mps2.y).sep().f32(
          s.accel_body_mps2.z);
      l.sep().f32(s.gyro_body_radps.x).sep().f32(s.gyro_body_radps.y).sep().f32(s.gyro_body_radps.z);
    });
    if (st != Status::kOk) return st;
  } else {
    remove_stale(dir + "/imu.csv");
  }

  if (!rec.truth.empty()) {
    bool attitude = false;
    for (const TruthRow& r : rec.truth) attitude = attitude || r.has_attitude;
    st = write_table(dir + "/truth.csv", tables::kTruth, attitude ? 4 : 0, rec.truth.size(),
                     [&](size_t i, csv::LineBuilder& l) {
                       const TruthRow& r = rec.truth[i];
                       l.time(r.t_us).sep().f64(r.pos_nav_m[0]).sep().f64(r.pos_nav_m[1]).sep().f64(
                           r.pos_nav_m[2]);
                       if (!attitude) return;
                       for (double q : r.q_nav_body) {
                         l.sep();
                         if (r.has_attitude) l.f64(q);
                       }
                     });
    if (st != Status::kOk) return st;
  } else {
    remove_stale(dir + "/truth.csv");
  }

  if (!rec.gnss.empty()) {
    st = write_gnss(dir + "/gnss.csv", rec.gnss);
    if (st != Status::kOk) return st;
  } else {
    remove_stale(dir + "/gnss.csv");
  }

  if (!rec.neighbours.empty()) {
    st = write_neighbours(dir + "/neighbours.csv", rec.neighbours);
    if (st != Status::kOk) return st;
  } else {
    remove_stale(dir + "/neighbours.csv");
  }

  return write_meta(dir + "/meta.ini", rec);
}

EstimatesWriter::EstimatesWriter() : line_(std::make_unique<csv::LineBuilder>()) {}

EstimatesWriter::~EstimatesWriter() { ignore_status(close()); }

Status EstimatesWriter::open(const std::string& path) {
  ignore_status(close());
  f_ = open_for_write(path);
  if (f_ == nullptr) return Status::kIoError;
  csv::LineBuilder l;
  l.text(csv::join(tables::kEstimates, 0).c_str());
  return l.flush_to(f_) ? Status::kOk : Status::kIoError;
}

Status EstimatesWriter::write(const NavOutput& out) {
  if (f_ == nullptr) return Status::kNotInitialised;
  csv::LineBuilder& l = *line_;
  l.time(out.t_us);
  l.sep().f32(out.pos_nav_m.x).sep().f32(out.pos_nav_m.y).sep().f32(out.pos_nav_m.z);
  l.sep().f32(out.vel_nav_mps.x).sep().f32(out.vel_nav_mps.y).sep().f32(out.vel_nav_mps.z);
  for (float q : out.q_nav_body) l.sep().f32(q);
  l.sep().f32(out.pos_sigma_m.x).sep().f32(out.pos_sigma_m.y).sep().f32(out.pos_sigma_m.z);
  l.sep().u64(static_cast<uint64_t>(out.status));
  return l.flush_to(f_) ? Status::kOk : Status::kIoError;
}

Status EstimatesWriter::close() {
  if (f_ == nullptr) return Status::kOk;
  const Status st = finish(f_, std::ferror(f_) == 0);
  f_ = nullptr;
  return st;
}

RangesWriter::RangesWriter() : line_(std::make_unique<csv::LineBuilder>()) {}

RangesWriter::~RangesWriter() { ignore_status(close()); }

Status RangesWriter::open(const std::string& path) {
  ignore_status(close());
  f_ = open_for_write(path);
  if (f_ == nullptr) return Status::kIoError;
  csv::LineBuilder l;
  l.text(csv::join(tables::kRanges, 0).c_str());
  return l.flush_to(f_) ? Status::kOk : Status::kIoError;
}

Status RangesWriter::write(const RangeReport& r) {
  if (f_ == nullptr) return Status::kNotInitialised;
  csv::LineBuilder& l = *line_;
  l.time(r.t_us).sep().u64(r.anchor_id).sep().u64(r.tag_id).sep().f32(r.range_m);
  l.sep().f32(r.innovation_m).sep().f32(r.p_svm).sep().f32(r.p_mc).sep().f32(r.p_fused);
  l.sep().u64(r.nlos ? 1U : 0U).sep().u64(r.used ? 1U : 0U);
  return l.flush_to(f_) ? Status::kOk : Status::kIoError;
}

Status RangesWriter::close() {
  if (f_ == nullptr) return Status::kOk;
  const Status st = finish(f_, std::ferror(f_) == 0);
  f_ = nullptr;
  return st;
}

Status read_estimates(const std::string& path, std::vector<EstimateRow>& out, ReadReport& report) {
  return read_output(path, tables::kEstimates, out, report, [](csv::Table& t, EstimateRow& r) {
    if (!t.parse_time(0, r.t_us)) return false;
    double* fields[13] = {&r.pos_nav_m[0],   &r.pos_nav_m[1],   &r.pos_nav_m[2],  &r.vel_nav_mps[0],
                          &r.vel_nav_mps[1], &r.vel_nav_mps[2], &r.q_nav_body[0], &r.q_nav_body[1],
                          &r.q_nav_body[2],  &r.q_nav_body[3],  &r.pos_sigma_m[0], &r.pos_sigma_m[1],
                          &r.pos_sigma_m[2]};
    for (size_t i = 0; i < 13; ++i) {
      if (!parse_double_or_nan(t, 1 + i, *fields[i])) return false;
    }
    uint64_t status = 0;
    if (!t.parse_uint(14, 255, status)) return false;
    r.status = static_cast<int>(status);
    t.accept_time(r.t_us);
    return true;
  });
}

Status read_ranges(const std::string& path, std::vector<RangeReport>& out, ReadReport& report) {
  return read_output(path, tables::kRanges, out, report, [](csv::Table& t, RangeReport& r) {
    uint64_t anchor = 0;
    uint64_t tag = 0;
    uint64_t nlos = 0;
    uint64_t used = 0;
    if (!t.parse_time(0, r.t_us) || !t.parse_uint(1, 0xFFFF, anchor) || !t.parse_uint(2, 0xFF, tag) ||
        !t.parse_float(3, r.range_m) || !t.parse_float_or_nan(4, r.innovation_m) ||
        !t.parse_float_or_nan(5, r.p_svm) || !t.parse_float_or_nan(6, r.p_mc) ||
        !t.parse_float_or_nan(7, r.p_fused) || !t.parse_uint(8, 1, nlos) || !t.parse_uint(9, 1, used)) {
      return false;
    }
    r.anchor_id = static_cast<uint16_t>(anchor);
    r.tag_id = static_cast<uint8_t>(tag);
    r.nlos = nlos != 0;
    r.used = used != 0;
    t.accept_time(r.t_us);
    return true;
  });
}

}  // namespace uwbnav::dataset
