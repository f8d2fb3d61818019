// static_points.csv reader (see static_points.hpp).
#include "tools/calib/static_points.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <system_error>

#include "tools/dataset/csv.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::calib {
namespace {

constexpr const char* kColumns = "point_id,t_start_s,t_end_s,x_m,y_m,z_m,yaw_deg";
constexpr double kPi = 3.14159265358979323846;
constexpr size_t kMaxErrors = 50;

std::string trim(const std::string& s) {
  size_t b = 0;
  size_t e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  return s.substr(b, e - b);
}

bool number(const std::string& cell, const char* what, double& out, std::string& why) {
  const char* b = cell.data();
  const char* e = b + cell.size();
  if (b < e && *b == '+') ++b;
  double v = 0.0;
  const auto r = std::from_chars(b, e, v, std::chars_format::general);
  if (cell.empty() || r.ec != std::errc() || r.ptr != e || !std::isfinite(v)) {
    why = std::string(what) + " " + dataset::csv::quote(cell.data(), cell.size()) + " is not a finite number";
    return false;
  }
  out = v;
  return true;
}

}  // namespace

Status parse_static_points(const std::string& text, const std::string& name, std::vector<StaticPoint>& out,
                           std::vector<std::string>& errors) {
  out.clear();
  bool failed = false;
  auto fail = [&](size_t line, const std::string& why) {
    failed = true;
    if (errors.size() < kMaxErrors) errors.push_back(name + ":" + std::to_string(line) + ": " + why);
  };
  size_t pos = 0;
  size_t line_no = 0;
  bool header = false;
  std::string line;
  while (dataset::csv::next_line(text, pos, line_no, line)) {
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (!header) {
      if (t != kColumns) {
        fail(line_no, "header must be '" + std::string(kColumns) + "'");
        return Status::kInvalidArgument;
      }
      header = true;
      continue;
    }
    std::vector<std::string> cells;
    size_t p = 0;
    for (;;) {
      const size_t c = t.find(',', p);
      cells.push_back(trim(t.substr(p, c == std::string::npos ? std::string::npos : c - p)));
      if (c == std::string::npos) break;
      p = c + 1;
    }
    if (cells.size() != 7) {
      fail(line_no, std::to_string(cells.size()) + " cells, expected 7 (" + kColumns + ")");
      continue;
    }
    StaticPoint sp;
    sp.id = cells[0];
    sp.line = line_no;
    double t0 = 0.0;
    double t1 = 0.0;
    std::string why;
    if (sp.id.empty()) {
      fail(line_no, "empty point_id");
      continue;
    }
    if (!number(cells[1], "t_start_s", t0, why) || !number(cells[2], "t_end_s", t1, why) ||
        !number(cells[3], "x_m", sp.pos_nav_m[0], why) || !number(cells[4], "y_m", sp.pos_nav_m[1], why) ||
        !number(cells[5], "z_m", sp.pos_nav_m[2], why)) {
      fail(line_no, why);
      continue;
    }
    if (!cells[6].empty()) {
      double yaw_deg = 0.0;
      if (!number(cells[6], "yaw_deg", yaw_deg, why)) {
        fail(line_no, why);
        continue;
      }
      sp.has_yaw = true;
      sp.yaw_rad = yaw_deg * kPi / 180.0;
    }
    if (t0 < 0.0 || !(t1 > t0)) {
      fail(line_no, "window [" + cells[1] + ", " + cells[2] + "] s is empty or negative (need 0 <= t_start_s < t_end_s)");
      continue;
    }
    sp.t_start_us = dataset::seconds_to_us(t0);
    sp.t_end_us = dataset::seconds_to_us(t1);
    out.push_back(sp);
  }
  if (!header) fail(line_no, "no header line '" + std::string(kColumns) + "'");
  std::vector<const StaticPoint*> sorted;
  for (const StaticPoint& sp : out) sorted.push_back(&sp);
  std::sort(sorted.begin(), sorted.end(),
            [](const StaticPoint* a, const StaticPoint* b) { return a->t_start_us < b->t_start_us; });
  for (size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i]->t_start_us < sorted[i - 1]->t_end_us) {
      fail(sorted[i]->line, "window of point " + sorted[i]->id + " overlaps point " + sorted[i - 1]->id +
                                " (line " + std::to_string(sorted[i - 1]->line) + ")");
    }
  }
  if (header && out.empty() && !failed) fail(line_no, "no static point rows");
  return failed ? Status::kInvalidArgument : Status::kOk;
}

Status read_static_points(const std::string& path, std::vector<StaticPoint>& out, std::vector<std::string>& errors) {
  std::string text;
  const Status s = dataset::csv::read_file(path, text);
  if (!ok(s)) {
    errors.push_back(path + ": " + (s == Status::kNotFound ? "no such file" : "cannot be read"));
    return s;
  }
  return parse_static_points(text, path, out, errors);
}

}  // namespace uwbnav::calib
