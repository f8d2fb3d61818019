// Labelled NLOS feature samples from recordings and feature tables.
#include "tools/eval/svm_features.hpp"

#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>
#include <utility>

#include "tools/dataset/text_source.hpp"
#include "tools/eval/metrics.hpp"

namespace uwbnav::eval {

bool parse_feature_set(const std::string& name, SvmFeatureSet* out) {
  if (name == "rr" || name == "range_rate") {
    *out = SvmFeatureSet::kRangeRate;
  } else if (name == "rrs" || name == "range_rate_speed") {
    *out = SvmFeatureSet::kRangeRateSpeed;
  } else if (name == "channel") {
    *out = SvmFeatureSet::kChannel;
  } else {
    return false;
  }
  return true;
}

const char* feature_set_name(SvmFeatureSet set) {
  switch (set) {
    case SvmFeatureSet::kRangeRate: return "range_rate";
    case SvmFeatureSet::kRangeRateSpeed: return "range_rate_speed";
    case SvmFeatureSet::kChannel: return "channel";
  }
  return "unknown";
}

double truth_speed_mps(const std::vector<dataset::TruthRow>& truth, uint64_t t_us, uint64_t dt_us) {
  double a[3];
  double b[3];
  const uint64_t t0 = t_us > dt_us ? t_us - dt_us : 0;
  const uint64_t t1 = t_us + dt_us;
  if (!truth_at(truth, t0, a) || !truth_at(truth, t1, b)) return std::nan("");
  const double dt_s = static_cast<double>(t1 - t0) * 1e-6;
  return std::hypot(b[0] - a[0], b[1] - a[1]) / dt_s;
}

Status samples_from_recording(const dataset::Recording& rec, SvmFeatureSet set, uint64_t max_dt_us,
                              std::vector<SvmSample>& out, std::string* error) {
  if (set == SvmFeatureSet::kRangeRateSpeed && rec.truth.empty()) {
    if (error != nullptr) *error = rec.name() + ": no truth for the speed feature";
    return Status::kInvalidArgument;
  }
  std::map<std::pair<int, int>, std::pair<uint64_t, float>> prev;  // (anchor, tag) -> (t, range)
  for (size_t i = 0; i < rec.uwb.size(); ++i) {
    const dataset::UwbRow& row = rec.uwb[i];
    const auto key = std::make_pair(static_cast<int>(row.range.anchor_id), static_cast<int>(row.range.tag_id));
    const auto it = prev.find(key);
    float range_rate_mps = std::nanf("");
    if (it != prev.end() && row.range.t_us > it->second.first && row.range.t_us - it->second.first <= max_dt_us) {
      const double dt_s = static_cast<double>(row.range.t_us - it->second.first) * 1e-6;
      range_rate_mps = static_cast<float>(static_cast<double>(row.range.range_m - it->second.second) / dt_s);
    }
    prev[key] = std::make_pair(row.range.t_us, row.range.range_m);
    if (row.nlos_label < 0) continue;
    float speed_mps = std::nanf("");
    if (set == SvmFeatureSet::kRangeRateSpeed) {
      speed_mps = static_cast<float>(truth_speed_mps(rec.truth, row.range.t_us));
    }
    SvmSample s;
    if (!svm_build_features(set, range_rate_mps, speed_mps, row.range.fp_power_dbm, row.range.rx_power_dbm,
                            s.features)) {
      continue;
    }
    s.label = row.nlos_label > 0 ? 1 : 0;
    s.group = row.range.anchor_id;
    s.source_index = i;
    out.push_back(s);
  }
  return Status::kOk;
}

namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream ss(line);
  while (std::getline(ss, cell, ',')) {
    if (!cell.empty() && cell.back() == '\r') cell.pop_back();
    cells.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

bool parse_double(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0' && std::isfinite(*out);
}

}  // namespace

Status samples_from_table(const std::string& path, SvmFeatureSet set, std::vector<SvmSample>& out,
                          std::string* error) {
  dataset::TextSource in;
  if (!ok(in.open(path))) {
    if (error != nullptr) *error = in.error();
    return Status::kIoError;
  }
  std::string line;
  if (!in.getline(line)) {
    if (error != nullptr) *error = in.status() != Status::kOk ? in.error() : path + ": empty";
    return Status::kIoError;
  }
  const std::vector<std::string> header = split_csv(line);
  std::map<std::string, size_t> col;
  for (size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  if (col.count("label") == 0 || col.count("fp_power_dbm") == 0 || col.count("rx_power_dbm") == 0) {
    if (error != nullptr) *error = path + ": needs columns label, fp_power_dbm, rx_power_dbm";
    return Status::kInvalidArgument;
  }
  if (set != SvmFeatureSet::kChannel) {
    if (error != nullptr) *error = path + ": a feature table only provides the channel feature set";
    return Status::kInvalidArgument;
  }
  const bool has_pos = col.count("height_cm") > 0 && col.count("horiz_dist_m") > 0;
  std::map<std::pair<long, long>, int> groups;
  size_t row_index = 0;
  while (in.getline(line)) {
    ++row_index;
    const std::vector<std::string> cells = split_csv(line);
    if (cells.size() < header.size()) continue;
    double label = 0.0;
    double fp = 0.0;
    double rx = 0.0;
    if (!parse_double(cells[col["label"]], &label) || !parse_double(cells[col["fp_power_dbm"]], &fp) ||
        !parse_double(cells[col["rx_power_dbm"]], &rx)) {
      continue;
    }
    SvmSample s;
    if (!svm_build_features(set, std::nanf(""), std::nanf(""), static_cast<float>(fp), static_cast<float>(rx),
                            s.features)) {
      continue;
    }
    s.label = label > 0.5 ? 1 : 0;
    s.source_index = row_index;
    if (has_pos) {
      double h = 0.0;
      double d = 0.0;
      if (parse_double(cells[col["height_cm"]], &h) && parse_double(cells[col["horiz_dist_m"]], &d)) {
        const auto key = std::make_pair(std::lround(h * 10.0), std::lround(d * 10.0));
        const auto it = groups.find(key);
        s.group = it != groups.end() ? it->second : (groups[key] = static_cast<int>(groups.size()));
      }
    }
    out.push_back(s);
  }
  if (!ok(in.status())) {
    if (error != nullptr) *error = in.error();
    return in.status();
  }
  return Status::kOk;
}

}  // namespace uwbnav::eval
