// Format v1 recording reader (docs/dataset-format.md): the whole recording
// into memory through the streaming reader (recording_stream.hpp), which skips
// bad rows with a "file:line: reason" warning each.
#include "tools/dataset/recording.hpp"

#include <cmath>

#include "tools/dataset/recording_stream.hpp"

namespace uwbnav::dataset {

std::string Recording::name() const { return recording_name(meta, dir); }

std::string recording_name(const std::map<std::string, std::string>& meta, const std::string& dir) {
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

namespace {

// Drains one stream into `rows`; kIoError (report.error set) when the file
// could not be read to its end.
template <typename Row>
Status drain(RowStream<Row>& stream, std::vector<Row>& rows, ReadReport& report) {
  Row row;
  while (stream.next(row)) rows.push_back(row);
  if (!ok(stream.status())) report.error = stream.error();
  return stream.status();
}

}  // namespace

Status read_recording(const std::string& dir, Recording& out, ReadReport& report) {
  out = Recording{};
  out.dir = dir;
  RecordingStream stream;
  Status st = stream.open(dir, report);
  if (!ok(st)) return st;
  out.meta = std::move(stream.meta);
  out.site = stream.site;
  out.gnss = std::move(stream.gnss);
  out.neighbours = std::move(stream.neighbours);
  st = drain(stream.uwb, out.uwb, report);
  if (ok(st)) st = drain(stream.imu, out.imu, report);
  if (ok(st)) st = drain(stream.truth, out.truth, report);
  return st;
}

std::vector<std::string> streams_ended_early(const Recording& rec) {
  if (rec.imu.empty() || rec.uwb.empty()) return {};
  return streams_ended_early(rec.imu.back().t_us, rec.uwb.back().range.t_us);
}

std::vector<std::string> streams_ended_early(uint64_t imu_end, uint64_t uwb_end) {
  std::vector<std::string> lines;
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
