// Site range calibration file: strict reader, site check, writer
// (format: docs/commissioning.md "Calibration file").
#include "tools/dataset/calibration.hpp"

#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "estimator/nlos/svm_model.hpp"
#include "tools/dataset/csv.hpp"

namespace uwbnav::dataset {
namespace {

constexpr const char* kColumns = "anchor_id,tag_id,offset_m,sigma_m";
constexpr double kMaxOffsetM = 10.0;  // an antenna delay is centimetres to decimetres; beyond: a typo [m]

std::string trim(const std::string& s) {
  size_t b = 0;
  size_t e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  return s.substr(b, e - b);
}

class Errors {
 public:
  Errors(std::vector<std::string>& out, const std::string& name) : out_(out), name_(name) {}
  void add(size_t line, const std::string& reason) {
    failed_ = true;
    if (out_.size() >= kMaxCalibrationErrors) return;
    out_.push_back(line == 0 ? name_ + ": " + reason : name_ + ":" + std::to_string(line) + ": " + reason);
  }
  bool failed() const { return failed_; }

 private:
  std::vector<std::string>& out_;
  const std::string& name_;
  bool failed_ = false;
};

// A whole-cell number: finite, no trailing characters. `what` names the column.
bool parse_number(const std::string& cell, const char* what, double& out, std::string& why) {
  const char* b = cell.data();
  const char* e = b + cell.size();
  if (b < e && *b == '+') ++b;
  double v = 0.0;
  const auto r = std::from_chars(b, e, v, std::chars_format::general);
  if (cell.empty() || r.ec != std::errc() || r.ptr != e) {
    why = std::string(what) + " " + csv::quote(cell.data(), cell.size()) + " is not a number";
    return false;
  }
  if (std::isnan(v)) {
    why = std::string(what) + " is NaN";
    return false;
  }
  if (!std::isfinite(v) || !std::isfinite(static_cast<float>(v))) {
    why = std::string(what) + " " + csv::quote(cell.data(), cell.size()) + " is not finite";
    return false;
  }
  out = v;
  return true;
}

bool parse_id(const std::string& cell, const char* what, uint64_t max_value, uint64_t& out, std::string& why) {
  const char* b = cell.data();
  const char* e = b + cell.size();
  uint64_t v = 0;
  const auto r = std::from_chars(b, e, v, 10);
  if (cell.empty() || r.ec != std::errc() || r.ptr != e || v > max_value) {
    why = std::string(what) + " " + csv::quote(cell.data(), cell.size()) + " is not an integer in 0.." +
          std::to_string(max_value);
    return false;
  }
  out = v;
  return true;
}

std::vector<std::string> split_commas(const std::string& line) {
  std::vector<std::string> cells;
  size_t pos = 0;
  for (;;) {
    const size_t c = line.find(',', pos);
    cells.push_back(trim(line.substr(pos, c == std::string::npos ? std::string::npos : c - pos)));
    if (c == std::string::npos) break;
    pos = c + 1;
  }
  return cells;
}

bool valid_key(const std::string& k) {
  if (k.empty()) return false;
  for (const char c : k) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  }
  return true;
}

// Rounds a sigma up to the 0.1 mm the file carries (never below 0.1 mm), so
// the written value is never smaller than the estimated one (by more than the
// 0.1 um a float holds of a value it cannot represent exactly).
double ceil_sigma(double s) {
  const double q = std::ceil(s * 1e4 - 1e-3) / 1e4;
  return q < 1e-4 ? 1e-4 : q;
}

uint32_t crc_u32(uint32_t crc, uint32_t v) {
  uint8_t b[4];
  for (size_t i = 0; i < 4; ++i) b[i] = static_cast<uint8_t>(v >> (8U * i));
  return crc32_update(crc, b, 4);
}

uint32_t crc_float(uint32_t crc, float f) {
  uint32_t bits = 0;
  std::memcpy(&bits, &f, sizeof bits);
  return crc_u32(crc, bits);
}

}  // namespace

uint32_t site_crc32(const SiteConfig& site) {
  uint32_t crc = 0;
  crc = crc_u32(crc, static_cast<uint32_t>(site.num_anchors));
  for (size_t i = 0; i < site.num_anchors; ++i) {
    const Anchor& a = site.anchors[i];
    crc = crc_u32(crc, a.id);
    crc = crc_float(crc, a.pos_nav_m.x);
    crc = crc_float(crc, a.pos_nav_m.y);
    crc = crc_float(crc, a.pos_nav_m.z);
  }
  crc = crc_u32(crc, static_cast<uint32_t>(site.num_tags));
  for (size_t i = 0; i < site.num_tags; ++i) {
    const Tag& t = site.tags[i];
    crc = crc_u32(crc, t.id);
    crc = crc_float(crc, t.lever_body_m.x);
    crc = crc_float(crc, t.lever_body_m.y);
    crc = crc_float(crc, t.lever_body_m.z);
  }
  return crc;
}

Status parse_calibration(const std::string& text, const std::string& name, CalibrationFile& out,
                         std::vector<std::string>& errors) {
  out = CalibrationFile{};
  Errors err(errors, name);
  size_t pos = 0;
  size_t line_no = 0;
  bool magic = false;
  bool header = false;
  size_t sigma_line = 0;
  std::vector<std::string> keys;
  std::string line;
  while (csv::next_line(text, pos, line_no, line)) {
    if (!magic) {
      if (trim(line) != kCalibrationMagic) {
        err.add(line_no, "first line must be '" + std::string(kCalibrationMagic) + "' (not a calibration file, or " +
                             "another format version)");
        return Status::kInvalidArgument;
      }
      magic = true;
      continue;
    }
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (!header) {
      if (t == kColumns) {
        header = true;
        continue;
      }
      const size_t eq = t.find('=');
      if (eq == std::string::npos) {
        err.add(line_no, "expected 'key = value' or the column line '" + std::string(kColumns) + "', got " +
                             csv::quote(t.data(), t.size()));
        continue;
      }
      const std::string key = trim(t.substr(0, eq));
      const std::string value = trim(t.substr(eq + 1));
      if (!valid_key(key)) {
        err.add(line_no, "key " + csv::quote(key.data(), key.size()) + " is not [a-z0-9_]+");
        continue;
      }
      bool seen = false;
      for (const auto& k : keys) seen = seen || k == key;
      if (seen) {
        err.add(line_no, "key '" + key + "' given twice");
        continue;
      }
      keys.push_back(key);
      if (key == "site_sigma_m") {
        double v = 0.0;
        std::string why;
        if (!parse_number(value, "site_sigma_m", v, why)) {
          err.add(line_no, why);
        } else if (!(v > 0.0) || v > 1.0) {
          err.add(line_no, "site_sigma_m " + value + " is not in (0, 1] m");
        } else {
          out.site_sigma_m = static_cast<float>(v);
          sigma_line = line_no;
        }
      } else if (key == "systematic_sigma_m") {
        double v = 0.0;
        std::string why;
        if (!parse_number(value, "systematic_sigma_m", v, why)) {
          err.add(line_no, why);
        } else if (!(v >= 0.0) || v > 1.0) {
          err.add(line_no, "systematic_sigma_m " + value + " is not in [0, 1] m");
        } else {
          out.systematic_sigma_m = static_cast<float>(v);
        }
      } else if (key == "site_crc32") {
        const char* b = value.data();
        const char* e = b + value.size();
        uint64_t v = 0;
        const bool hex = value.size() > 2 && value[0] == '0' && (value[1] == 'x' || value[1] == 'X');
        const auto r = hex ? std::from_chars(b + 2, e, v, 16) : std::from_chars_result{b, std::errc::invalid_argument};
        if (!hex || r.ec != std::errc() || r.ptr != e || v > 0xFFFFFFFFULL) {
          err.add(line_no, "site_crc32 " + csv::quote(value.data(), value.size()) + " is not 0x followed by hex digits");
        } else {
          out.has_site_crc = true;
          out.site_crc32 = static_cast<uint32_t>(v);
          out.site_crc_line = line_no;
        }
      } else {
        out.info.push_back(key + " = " + value);
      }
      continue;
    }
    const std::vector<std::string> cells = split_commas(t);
    if (cells.size() != 4) {
      err.add(line_no, std::to_string(cells.size()) + " cells, expected 4 (" + kColumns + ")");
      continue;
    }
    uint64_t anchor = 0;
    uint64_t tag = 0;
    double offset = 0.0;
    double sigma = 0.0;
    std::string why;
    if (!parse_id(cells[0], "anchor_id", 0xFFFF, anchor, why) || !parse_id(cells[1], "tag_id", 0xFF, tag, why) ||
        !parse_number(cells[2], "offset_m", offset, why) || !parse_number(cells[3], "sigma_m", sigma, why)) {
      err.add(line_no, why);
      continue;
    }
    if (std::fabs(offset) > kMaxOffsetM) {
      err.add(line_no, "offset_m " + cells[2] + " is beyond +-10 m (not an antenna delay)");
      continue;
    }
    if (!(sigma > 0.0) || sigma > 1.0) {
      err.add(line_no, "sigma_m " + cells[3] + " is not in (0, 1] m");
      continue;
    }
    bool dup = false;
    for (const CalibrationPair& p : out.pairs) {
      if (p.anchor_id == anchor && p.tag_id == tag) {
        err.add(line_no, "duplicate pair anchor " + std::to_string(anchor) + " / tag " + std::to_string(tag) +
                             " (first on line " + std::to_string(p.line) + ")");
        dup = true;
        break;
      }
    }
    if (dup) continue;
    CalibrationPair p;
    p.anchor_id = static_cast<uint16_t>(anchor);
    p.tag_id = static_cast<uint8_t>(tag);
    p.offset_m = static_cast<float>(offset);
    p.sigma_m = static_cast<float>(sigma);
    p.line = line_no;
    out.pairs.push_back(p);
  }
  if (!magic) {
    err.add(0, "empty file (first line must be '" + std::string(kCalibrationMagic) + "')");
    return Status::kInvalidArgument;
  }
  if (std::isnan(out.site_sigma_m) && sigma_line == 0) {
    bool given = false;
    for (const auto& k : keys) given = given || k == "site_sigma_m";
    if (!given) err.add(0, "no 'site_sigma_m = <metres>' line before the column line");
  }
  if (!header) {
    err.add(0, "no column line '" + std::string(kColumns) + "'");
  } else if (out.pairs.empty() && !err.failed()) {
    err.add(0, "no pair rows");
  }
  if (!std::isnan(out.site_sigma_m)) {
    for (const CalibrationPair& p : out.pairs) {
      if (p.sigma_m > out.site_sigma_m) {
        err.add(p.line, "sigma_m of anchor " + std::to_string(p.anchor_id) + " / tag " + std::to_string(p.tag_id) +
                            " exceeds site_sigma_m (line " + std::to_string(sigma_line) +
                            "): the site sigma must cover every pair");
      }
    }
  }
  return err.failed() ? Status::kInvalidArgument : Status::kOk;
}

Status check_calibration(const CalibrationFile& cal, const SiteConfig& site, const std::string& name,
                         std::vector<std::string>& errors) {
  Errors err(errors, name);
  if (cal.has_site_crc) {
    const uint32_t crc = site_crc32(site);
    if (crc != cal.site_crc32) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "site_crc32 0x%08" PRIx32 " does not match this site (0x%08" PRIx32
                    "): the offsets were made for another anchor survey or tag layout",
                    cal.site_crc32, crc);
      err.add(cal.site_crc_line, buf);
    }
  }
  bool seen[kMaxAnchors][kMaxTags] = {};
  for (const CalibrationPair& p : cal.pairs) {
    const int a = site.find_anchor(p.anchor_id);
    const int t = site.find_tag(p.tag_id);
    if (a < 0) {
      err.add(p.line, "anchor " + std::to_string(p.anchor_id) + " is not an anchor of the site");
      continue;
    }
    if (t < 0) {
      err.add(p.line, "tag " + std::to_string(p.tag_id) + " is not a tag of the site");
      continue;
    }
    seen[a][t] = true;
  }
  for (size_t a = 0; a < site.num_anchors; ++a) {
    for (size_t t = 0; t < site.num_tags; ++t) {
      if (!seen[a][t]) {
        err.add(0, "no row for anchor " + std::to_string(site.anchors[a].id) + " / tag " +
                       std::to_string(site.tags[t].id) + " of the site (every pair must be calibrated)");
      }
    }
  }
  return err.failed() ? Status::kInvalidArgument : Status::kOk;
}

void apply_calibration(const CalibrationFile& cal, SiteConfig& site) {
  for (auto& row : site.range_offset_m) {
    for (float& v : row) v = 0.0F;
  }
  for (const CalibrationPair& p : cal.pairs) {
    const int a = site.find_anchor(p.anchor_id);
    const int t = site.find_tag(p.tag_id);
    if (a >= 0 && t >= 0) site.range_offset_m[a][t] = p.offset_m;
  }
  site.range_offset_sigma_m = cal.site_sigma_m;
  site.range_systematic_sigma_m = cal.systematic_sigma_m;
}

Status load_calibration(const std::string& path, SiteConfig& site, std::vector<std::string>& errors) {
  std::string text;
  const Status rs = csv::read_file(path, text);
  if (!ok(rs)) {
    errors.push_back(path + ": " + (rs == Status::kNotFound ? "no such file" : "cannot be read"));
    return rs;
  }
  CalibrationFile cal;
  if (!ok(parse_calibration(text, path, cal, errors))) return Status::kInvalidArgument;
  if (!ok(check_calibration(cal, site, path, errors))) return Status::kInvalidArgument;
  apply_calibration(cal, site);
  return Status::kOk;
}

std::string format_calibration(const CalibrationFile& cal) {
  std::string s = std::string(kCalibrationMagic) + "\n";
  char buf[160];
  std::snprintf(buf, sizeof buf, "site_sigma_m = %.4f\n", ceil_sigma(static_cast<double>(cal.site_sigma_m)));
  s += buf;
  if (std::isfinite(cal.systematic_sigma_m)) {
    std::snprintf(buf, sizeof buf, "systematic_sigma_m = %.4f\n", ceil_sigma(static_cast<double>(cal.systematic_sigma_m)));
    s += buf;
  }
  if (cal.has_site_crc) {
    std::snprintf(buf, sizeof buf, "site_crc32 = 0x%08" PRIx32 "\n", cal.site_crc32);
    s += buf;
  }
  for (const std::string& i : cal.info) s += i + "\n";
  s += std::string(kColumns) + "\n";
  for (const CalibrationPair& p : cal.pairs) {
    std::snprintf(buf, sizeof buf, "%u,%u,%.4f,%.4f\n", static_cast<unsigned>(p.anchor_id),
                  static_cast<unsigned>(p.tag_id), static_cast<double>(p.offset_m),
                  ceil_sigma(static_cast<double>(p.sigma_m)));
    s += buf;
  }
  return s;
}

Status write_calibration(const std::string& path, const CalibrationFile& cal) {
  const std::string text = format_calibration(cal);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return Status::kIoError;
  const bool wrote = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const bool closed = std::fclose(f) == 0;
  return wrote && closed ? Status::kOk : Status::kIoError;
}

}  // namespace uwbnav::dataset
