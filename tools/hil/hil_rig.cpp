// HIL test bench: real-time playback over a CAN link and the report (see hil_rig.hpp).
#include "tools/hil/hil_rig.hpp"

#include <poll.h>

#include <algorithm>
#include <cmath>
#include <ctime>

#include "firmware/app.hpp"
#include "tools/eval/replay.hpp"

namespace uwbnav::hil {
namespace {

uint64_t monotonic_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000U + static_cast<uint64_t>(ts.tv_nsec) / 1000U;
}

// Waits until the bus fd is readable or timeout_us passed.
void wait_readable(int fd, uint64_t timeout_us) {
  pollfd p{};
  p.fd = fd;
  p.events = POLLIN;
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(timeout_us / 1000000U);
  ts.tv_nsec = static_cast<long>((timeout_us % 1000000U) * 1000U);
  ignore_result(::ppoll(&p, 1, &ts, nullptr) > 0);
}

uint64_t add_signed(uint64_t t_us, int64_t offset_us) {
  return static_cast<uint64_t>(static_cast<int64_t>(t_us) + offset_us);
}

void log_frame(hal::CandumpLogWriter* log, const hal::CanFrame& f) {
  if (log != nullptr && log->is_open()) ignore_status(log->write(f));
}

// Waits for the firmware's first UWBNAV_NavTime; with align, keeps reading
// for the alignment window and returns max(nav_t - arrival) as the clock offset
// (a lower bound of the true offset, short by the smallest transfer delay).
Status wait_for_firmware(hal::SocketCanBus& bus, const RigOptions& o, int64_t* offset_us, std::string* error) {
  const uint64_t give_up_us = monotonic_us() + o.wait_output_us;
  bool seen = false;
  uint64_t align_end_us = 0;
  int64_t best = INT64_MIN;
  for (;;) {
    const uint64_t now = monotonic_us();
    if (seen && now >= align_end_us) break;
    if (!seen && now >= give_up_us) {
      if (error) *error = "no UWBNAV_NavTime frame from the firmware within " +
                          std::to_string(o.wait_output_us / 1000000U) + " s (firmware running? can.tx_enable = 1?)";
      return Status::kEmpty;
    }
    if (o.stop != nullptr && *o.stop) {
      if (error) *error = "interrupted while waiting for the firmware";
      return Status::kEmpty;
    }
    wait_readable(bus.fd(), 5000);
    hal::CanFrame f;
    for (;;) {
      const Status s = bus.receive(f);
      if (s == Status::kIoError) {
        if (error) *error = "link closed while waiting for the firmware: " + bus.last_error();
        return Status::kIoError;
      }
      if (!ok(s)) break;
      log_frame(o.rx_log, f);
      can::NavTimeMsg m;
      if (f.id != can::id_of(can::MsgId::kNavTime) || !ok(can::decode(f, m))) continue;
      if (!seen) {
        seen = true;
        align_end_us = monotonic_us() + (o.align_clock ? o.align_us : 0);
      }
      best = std::max(best, static_cast<int64_t>(m.nav_t_us) - static_cast<int64_t>(f.t_us));
    }
  }
  *offset_us = o.align_clock ? best : 0;
  return Status::kOk;
}

void drain(hal::SocketCanBus& bus, const RigOptions& o, RigRun& run) {
  hal::CanFrame f;
  for (;;) {
    const Status s = bus.receive(f);
    if (s == Status::kIoError) {
      run.link_closed = true;
      return;
    }
    if (!ok(s)) return;
    ++run.frames_received;
    log_frame(o.rx_log, f);
    run.monitor->on_frame(f, add_signed(f.t_us, run.clock_offset_us));
  }
}

}  // namespace

Status run_rig(const dataset::Recording& rec, hal::SocketCanBus& bus, const RigOptions& o, RigRun& run,
               std::string* error) {
  run = RigRun{};
  if (!(o.speed > 0.0)) {
    if (error) *error = "speed must be > 0";
    return Status::kInvalidArgument;
  }
  const Status waited = wait_for_firmware(bus, o, &run.clock_offset_us, error);
  if (!ok(waited)) return waited;

  const uint64_t start_fw_us = add_signed(monotonic_us(), run.clock_offset_us) + o.lead_us;
  run.stream = std::make_unique<SensorStream>(rec, map_recording_to_clock(rec, start_fw_us, o.speed));
  run.monitor = std::make_unique<OutputMonitor>(run.stream.get());
  const SensorStream& stream = *run.stream;
  const uint64_t end_fw_us = stream.last_clock_us() + o.tail_us;

  can::CanSensorEncoder encoder;
  hal::CanFrame frames[can::kImuFrames];
  size_t next = 0;
  const uint64_t wall0_us = monotonic_us();
  uint64_t next_progress_us = wall0_us + o.progress_every_us;
  size_t latency_seen = 0;
  double latency_max_us = 0.0;
  for (;;) {
    const uint64_t now_fw_us = add_signed(monotonic_us(), run.clock_offset_us);
    // Send every sample that is due: a sensor delivers its sample at (not before) its timestamp.
    while (next < stream.size() && stream[next].t_clock_us <= now_fw_us && !run.link_closed) {
      const size_t n = stream.encode(next, encoder, frames);
      bool all_sent = true;
      for (size_t k = 0; k < n; ++k) {
        frames[k].t_us = add_signed(now_fw_us, -run.clock_offset_us);
        const Status s = bus.send(frames[k]);
        if (ok(s)) {
          ++run.frames_sent;
          log_frame(o.tx_log, frames[k]);
        } else if (s == Status::kWouldBlock) {
          ++run.tx_dropped;
          all_sent = false;
        } else {
          ++run.tx_failed;
          all_sent = false;
          if (bus.state() == hal::CanBusState::kDown) run.link_closed = true;
        }
      }
      if (all_sent) ++(stream[next].kind == StreamKind::kImu ? run.imu_sent : run.uwb_sent);
      run.send_late_max_us = std::max(run.send_late_max_us, now_fw_us - stream[next].t_clock_us);
      ++next;
    }
    drain(bus, o, run);
    if (o.progress != nullptr && monotonic_us() >= next_progress_us) {
      next_progress_us += o.progress_every_us;
      const auto& lat = run.monitor->latencies_us();
      for (; latency_seen < lat.size(); ++latency_seen) latency_max_us = std::max(latency_max_us, lat[latency_seen]);
      const double total_s = static_cast<double>(end_fw_us - start_fw_us) * 1e-6;
      const double done_s = std::min(total_s, static_cast<double>(now_fw_us - std::min(now_fw_us, start_fw_us)) * 1e-6);
      std::fprintf(o.progress, "hil: %5.1f of %.1f s played, %zu solutions received, %llu frames sent, latency max so far %.2f ms\n",
                   done_s, total_s, run.monitor->solutions().size(), static_cast<unsigned long long>(run.frames_sent),
                   latency_max_us * 1e-3);
      std::fflush(o.progress);
    }
    if (run.link_closed) break;
    if (next >= stream.size() && now_fw_us >= end_fw_us) break;
    if (o.stop != nullptr && *o.stop) {
      run.interrupted = true;
      break;
    }
    const uint64_t wake_fw_us = next < stream.size() ? stream[next].t_clock_us : end_fw_us;
    const uint64_t now2_fw_us = add_signed(monotonic_us(), run.clock_offset_us);
    if (wake_fw_us > now2_fw_us) wait_readable(bus.fd(), std::min<uint64_t>(wake_fw_us - now2_fw_us, 20000));
  }
  run.played_s = static_cast<double>(monotonic_us() - wall0_us) * 1e-6;
  if (run.link_closed && error) *error = "link closed by the firmware: " + bus.last_error();
  return Status::kOk;
}

SeriesStats series_stats(const std::vector<double>& v) {
  SeriesStats s;
  s.n = v.size();
  if (v.empty()) {
    s.mean = s.std = s.min = s.p50 = s.p95 = s.p99 = s.max = std::nan("");
    return s;
  }
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.std = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
  s.min = *std::min_element(v.begin(), v.end());
  s.max = *std::max_element(v.begin(), v.end());
  s.p50 = eval::quantile(v, 0.50);
  s.p95 = eval::quantile(v, 0.95);
  s.p99 = eval::quantile(v, 0.99);
  return s;
}

namespace {

std::vector<double> scaled(const std::vector<double>& v, double k) {
  std::vector<double> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = v[i] * k;
  return out;
}

eval::AccuracyStats accuracy_vs_truth(const std::vector<dataset::EstimateRow>& rows,
                                      const std::vector<dataset::TruthRow>& truth) {
  if (truth.empty()) return eval::AccuracyStats{};
  size_t total = 0;
  for (const auto& r : rows) total += (r.t_us >= truth.front().t_us && r.t_us <= truth.back().t_us) ? 1 : 0;
  return eval::accuracy(eval::compare_with_truth(rows, truth), total);
}

}  // namespace

HilReport build_report(const dataset::Recording& rec, const RigRun& run, bool lockstep) {
  HilReport r;
  r.recording = rec.name();
  r.speed = run.stream ? run.stream->map().speed : 1.0;
  r.played_s = run.played_s;
  r.clock_offset_us = run.clock_offset_us;
  r.imu_sent = run.imu_sent;
  r.uwb_sent = run.uwb_sent;
  r.frames_sent = run.frames_sent;
  r.tx_dropped = run.tx_dropped;
  r.tx_failed = run.tx_failed;
  r.send_late_max_us = run.send_late_max_us;
  r.frames_received = run.frames_received;
  r.interrupted = run.interrupted;
  r.link_closed = run.link_closed;
  if (run.monitor) {
    const OutputMonitor& m = *run.monitor;
    r.latency_ms = series_stats(scaled(m.latencies_us(), 1e-3));
    r.latency_hist.assign(kNumLatencyBins, 0);
    for (double us : m.latencies_us()) {
      ++r.latency_hist[latency_bin(us > 4.0e9 ? 4000000000U : static_cast<uint32_t>(std::max(0.0, us)))];
    }
    const std::vector<double> periods_ms = scaled(m.periods_us(), 1e-3);
    r.period_ms = series_stats(periods_ms);
    for (double p : periods_ms) r.period_max_dev_ms = std::max(r.period_max_dev_ms, std::fabs(p - 10.0));
    r.messages = m.messages();
    r.missing = m.total_missing();
    r.e2e_failures = m.total_e2e_failures();
    r.group_mismatches = m.group_mismatches();
    r.other_frames = m.other_frames();
    r.have_diag = m.have_diag();
    r.fw_overruns = m.last_diag().overruns;
    r.fw_input_rejects = m.last_diag().input_rejects;
    r.solutions = m.solutions().size();
    if (run.stream) r.hil = accuracy_vs_truth(solutions_to_estimates(m.solutions(), run.stream->map()), rec.truth);
  }
  if (lockstep && !rec.truth.empty()) {
    eval::ReplayOptions opt;
    eval::ReplayResult res;
    std::string err;
    if (ok(eval::run_replay(rec, opt, res, &err))) {
      r.have_lockstep = true;
      r.lockstep = accuracy_vs_truth(res.estimates, rec.truth);
    }
  }
  return r;
}

namespace {

// Lines shared by the stdout table and the markdown report: label, value.
std::vector<std::pair<std::string, std::string>> report_rows(const HilReport& r) {
  char b[256];
  std::vector<std::pair<std::string, std::string>> rows;
  auto add = [&](const char* k) { rows.emplace_back(k, b); };
  std::snprintf(b, sizeof b, "%s, speed %.2f, %.1f s played%s%s", r.recording.c_str(), r.speed, r.played_s,
                r.interrupted ? " (interrupted)" : "", r.link_closed ? " (link closed)" : "");
  add("recording");
  std::snprintf(b, sizeof b, "%s, firmware clock offset %lld us", r.link.c_str(),
                static_cast<long long>(r.clock_offset_us));
  add("link");
  std::snprintf(b, sizeof b, "%llu IMU + %llu UWB samples, %llu frames, %llu refused, %llu failed, send lateness max %.2f ms",
                static_cast<unsigned long long>(r.imu_sent), static_cast<unsigned long long>(r.uwb_sent),
                static_cast<unsigned long long>(r.frames_sent), static_cast<unsigned long long>(r.tx_dropped),
                static_cast<unsigned long long>(r.tx_failed), static_cast<double>(r.send_late_max_us) * 1e-3);
  add("rig sent");
  std::snprintf(b, sizeof b, "%llu frames, %zu solutions", static_cast<unsigned long long>(r.frames_received),
                r.solutions);
  add("received");
  std::snprintf(b, sizeof b, "n %zu  mean %.2f  p50 %.2f  p95 %.2f  p99 %.2f  max %.2f ms", r.latency_ms.n,
                r.latency_ms.mean, r.latency_ms.p50, r.latency_ms.p95, r.latency_ms.p99, r.latency_ms.max);
  add("latency e2e");
  if (!r.latency_hist.empty()) {
    std::string h;
    for (uint32_t i = 0; i < kNumLatencyBins && i < r.latency_hist.size(); ++i) {
      char bin[48];
      if (i + 1 < kNumLatencyBins) {
        std::snprintf(bin, sizeof bin, "%s<=%u:%u", i ? " " : "", kLatencyBinUpperUs[i], r.latency_hist[i]);
      } else {
        std::snprintf(bin, sizeof bin, " >%u:%u", kLatencyBinUpperUs[kNumLatencyBins - 2], r.latency_hist[i]);
      }
      h += bin;
    }
    rows.emplace_back("latency histogram", "solutions per bin [us] " + h);
  }
  std::snprintf(b, sizeof b, "mean %.3f  std %.3f  min %.2f  max %.2f ms, max |dev from 10 ms| %.2f ms",
                r.period_ms.mean, r.period_ms.std, r.period_ms.min, r.period_ms.max, r.period_max_dev_ms);
  add("PosXY period");
  std::snprintf(b, sizeof b, "%u missing (counter gaps), %u E2E failures, %u group mismatches, %u foreign frames",
                r.missing, r.e2e_failures, r.group_mismatches, r.other_frames);
  add("dropped");
  for (const auto& m : r.messages) {
    std::snprintf(b, sizeof b, "%u rx, %u ok, %u missing, %u repeated, %u crc, %u len, %u ctr15, %u saturated",
                  m.received, m.accepted, m.missing, m.repeated, m.crc_errors, m.length_errors, m.counter_errors,
                  m.saturated);
    rows.emplace_back(std::string("  ") + m.name, b);
  }
  if (r.have_diag) {
    std::snprintf(b, sizeof b, "loop overruns %llu, input rejects %u (UWBNAV_Diag)",
                  static_cast<unsigned long long>(r.fw_overruns), r.fw_input_rejects);
  } else {
    std::snprintf(b, sizeof b, "no UWBNAV_Diag received");
  }
  add("firmware");
  if (!r.firmware_latency.empty()) rows.emplace_back("firmware cycles", r.firmware_latency);
  std::snprintf(b, sizeof b, "RMSE %.3f m  MAX %.3f m  STD %.3f m  (%zu of %zu epochs)", r.hil.rmse_h_m,
                r.hil.max_h_m, r.hil.std_h_m, r.hil.epochs, r.hil.epochs_total);
  add("position (HIL)");
  if (r.have_lockstep) {
    std::snprintf(b, sizeof b, "RMSE %.3f m  MAX %.3f m  STD %.3f m  (%zu of %zu epochs)", r.lockstep.rmse_h_m,
                  r.lockstep.max_h_m, r.lockstep.std_h_m, r.lockstep.epochs, r.lockstep.epochs_total);
    add("position (lockstep)");
  }
  return rows;
}

}  // namespace

std::vector<std::string> check_report(const HilReport& r, const HilLimits& limits, int* failures) {
  std::vector<std::string> lines;
  auto check = [&](const char* what, double value, double bound, bool pass) {
    char b[200];
    std::snprintf(b, sizeof b, "CHECK %s: %s = %.4f %s %.4f", pass ? "passed" : "FAILED", what, value,
                  pass ? "<=" : "exceeds", bound);
    lines.emplace_back(b);
    if (!pass) ++*failures;
  };
  if (limits.max_missing >= 0.0) {
    const double v = static_cast<double>(r.missing) + r.e2e_failures + r.group_mismatches;
    check("missing + E2E failures + group mismatches", v, limits.max_missing, v <= limits.max_missing);
  }
  if (limits.max_latency_ms >= 0.0) {
    check("latency max [ms]", r.latency_ms.max, limits.max_latency_ms,
          r.latency_ms.n > 0 && r.latency_ms.max <= limits.max_latency_ms);
  }
  if (limits.max_latency_p99_ms >= 0.0) {
    check("latency p99 [ms]", r.latency_ms.p99, limits.max_latency_p99_ms,
          r.latency_ms.n > 0 && r.latency_ms.p99 <= limits.max_latency_p99_ms);
  }
  if (limits.max_rmse_m >= 0.0) {
    check("horizontal RMSE [m]", r.hil.rmse_h_m, limits.max_rmse_m,
          r.hil.epochs > 0 && r.hil.rmse_h_m <= limits.max_rmse_m);
  }
  return lines;
}

void print_report(std::FILE* out, const HilReport& r) {
  std::fprintf(out, "HIL report\n");
  for (const auto& [k, v] : report_rows(r)) std::fprintf(out, "  %-20s %s\n", k.c_str(), v.c_str());
  // Machine-readable summary line (tests/scripts/hil.cmake parses it).
  std::fprintf(out,
               "HIL_SUMMARY solutions=%zu missing=%u e2e_failures=%u group_mismatches=%u latency_p99_ms=%.3f "
               "latency_max_ms=%.3f period_std_ms=%.3f rmse_h_m=%.4f max_h_m=%.4f lockstep_rmse_h_m=%.4f\n",
               r.solutions, r.missing, r.e2e_failures, r.group_mismatches, r.latency_ms.p99, r.latency_ms.max,
               r.period_ms.std, r.hil.rmse_h_m, r.hil.max_h_m, r.have_lockstep ? r.lockstep.rmse_h_m : std::nan(""));
}

Status write_report_markdown(const std::string& path, const HilReport& r) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return Status::kIoError;
  std::fprintf(f, "# HIL report: %s\n\n", r.recording.c_str());
  std::fprintf(f, "Definitions: docs/hil.md. Times in ms, positions horizontal in m.\n\n");
  std::fprintf(f, "| item | value |\n|---|---|\n");
  for (const auto& [k, v] : report_rows(r)) std::fprintf(f, "| %s | %s |\n", k.c_str(), v.c_str());
  return std::fclose(f) == 0 ? Status::kOk : Status::kIoError;
}

}  // namespace uwbnav::hil
