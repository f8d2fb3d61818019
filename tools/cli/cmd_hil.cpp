// `uwbnav hil RECORDING`: the HIL test bench. Plays a recording in real time
// into a firmware over a CAN link as HIL sensor frames, reads the firmware's
// CAN output back and reports latency, jitter, dropped frames and position error.
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "hal/host/candump_log.hpp"
#include "hal/host/socketcan_bus.hpp"
#include "tools/cli/args.hpp"
#include "tools/dataset/fs.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/hil/child_process.hpp"
#include "tools/hil/hil_rig.hpp"

namespace uwbnav::cli {
namespace {

volatile bool g_hil_stop = false;
void on_hil_signal(int) { g_hil_stop = true; }

uint64_t clock_us(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000U + static_cast<uint64_t>(ts.tv_nsec) / 1000U;
}

bool parse_double(const std::string& s, double* out) {
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == '\0';
}

// Connects to the spawned firmware's link, retrying while it starts up.
Status connect_to_child(const std::string& path, int pid, int& fd, std::string* error) {
  const uint64_t give_up_us = clock_us(CLOCK_MONOTONIC) + 15000000U;
  while (clock_us(CLOCK_MONOTONIC) < give_up_us && !g_hil_stop) {
    int code = 0;
    if (!hil::child_running(pid, &code)) {
      if (error) *error = "the firmware exited during start-up (exit code " + std::to_string(code) + ")";
      return Status::kIoError;
    }
    const Status s = hal::can_link_connect(path, fd, error);
    if (ok(s)) return s;
    if (s != Status::kNotFound) return s;
    const timespec ts{0, 20 * 1000 * 1000};
    ::nanosleep(&ts, nullptr);
  }
  if (error) *error = "the firmware did not open " + path + " within 15 s";
  return Status::kEmpty;
}

// The cycle-latency histogram line of the spawned firmware's exit summary
// ("  latency  deadline to end of work: ..."), without its label; "" when absent.
std::string firmware_latency_line(const std::string& log_path) {
  std::FILE* f = std::fopen(log_path.c_str(), "r");
  if (f == nullptr) return "";
  char line[512];
  std::string found;
  const char* const kLabel = "  latency  ";
  while (std::fgets(line, sizeof line, f) != nullptr) {
    if (std::strncmp(line, kLabel, std::strlen(kLabel)) == 0) {
      found = line + std::strlen(kLabel);
      while (!found.empty() && (found.back() == '\n' || found.back() == '\r')) found.pop_back();
    }
  }
  std::fclose(f);
  return found;
}

}  // namespace

int cmd_hil(int argc, char** argv) {
  Args args(argc, argv, {"--spawn", "--align", "--no-lockstep"});
  const std::vector<std::string> known = {"--link",         "--can-if",      "--spawn",       "--speed",
                                          "--out",          "--align",       "--param",       "--no-lockstep",
                                          "--max-missing",  "--max-latency-ms", "--max-rmse-m",
                                          "--max-latency-p99-ms"};
  double speed = 1.0;
  double max_latency_ms = 0.0;
  double max_latency_p99_ms = 0.0;
  double max_rmse_m = 0.0;
  uint64_t max_missing = 0;
  const bool bad_numbers = !parse_double(args.get("--speed", "1.0"), &speed) || !(speed > 0.0) ||
                           !parse_double(args.get("--max-latency-ms", "0"), &max_latency_ms) ||
                           !parse_double(args.get("--max-latency-p99-ms", "0"), &max_latency_p99_ms) ||
                           !parse_double(args.get("--max-rmse-m", "0"), &max_rmse_m) ||
                           !args.get_u64("--max-missing", 0, &max_missing);
  if (!args.error().empty() || args.positional().size() != 1 || !args.unknown(known).empty() || bad_numbers ||
      (args.has("--can-if") && (args.has("--link") || args.has("--spawn")))) {
    std::fprintf(stderr,
                 "usage: uwbnav hil RECORDING [--link PATH [--spawn] | --can-if NAME] [--speed S] [--out DIR]\n"
                 "                  [--align] [--param name=value]... [--no-lockstep]\n"
                 "                  [--max-missing N] [--max-latency-ms MS] [--max-latency-p99-ms MS] [--max-rmse-m M]\n"
                 "  --spawn starts `uwbnav firmware --can-link PATH --site RECORDING --console none` itself;\n"
                 "  --max-* turn the report into a pass/fail check (exit code 3 on failure): --max-latency-ms\n"
                 "  bounds the largest end-to-end latency, --max-latency-p99-ms its 99th percentile.\n"
                 "  A progress line goes to stderr every 5 s while playing.\n");
    return 2;
  }
  const std::string rec_dir = args.positional()[0];
  dataset::Recording rec;
  dataset::ReadReport read_report;
  if (!ok(dataset::read_recording(rec_dir, rec, read_report))) {
    std::fprintf(stderr, "uwbnav hil: cannot read recording %s: %s\n", rec_dir.c_str(), read_report.error.c_str());
    return 1;
  }
  const std::string out = args.get("--out");
  dataset::OutputDir out_dir;  // removed again unless the rig played
  if (!out.empty() && !out_dir.create(out)) {
    std::fprintf(stderr, "uwbnav hil: cannot create %s\n", out.c_str());
    return 1;
  }
  const bool spawn = args.has("--spawn");
  const bool socketcan = args.has("--can-if");
  const std::string link = args.get("--link", spawn ? "/tmp/uwbnav-hil-" + std::to_string(::getpid()) + ".sock"
                                                    : "/tmp/uwbnav-can.sock");

  struct sigaction sa {};
  sa.sa_handler = on_hil_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);

  int child = -1;
  if (spawn) {
    ::unlink(link.c_str());
    std::vector<std::string> child_args = {"uwbnav", "firmware", "--can-link", link, "--site", rec_dir,
                                           "--console", "none"};
    if (!out.empty()) {
      child_args.push_back("--can-log");
      child_args.push_back(out + "/firmware_can.log");
    }
    for (const auto& p : args.all("--param")) {
      child_args.push_back("--param");
      child_args.push_back(p);
    }
    std::string err;
    if (!ok(hil::spawn_self(child_args, out.empty() ? "" : out + "/firmware.log", &child, &err))) {
      std::fprintf(stderr, "uwbnav hil: cannot start the firmware: %s\n", err.c_str());
      return 1;
    }
    std::printf("hil: started firmware (pid %d) on %s\n", child, link.c_str());
  }

  hal::SocketCanBus bus;
  std::string err;
  Status opened = Status::kOk;
  if (socketcan) {
    opened = bus.open(args.get("--can-if"));
    if (!ok(opened)) err = "cannot open CAN interface " + args.get("--can-if") + ": " + bus.last_error();
  } else {
    int fd = -1;
    opened = spawn ? connect_to_child(link, child, fd, &err) : hal::can_link_connect(link, fd, &err);
    if (!ok(opened) && !spawn) err += " (start `uwbnav firmware --can-link " + link + " --site " + rec_dir + "` first, or use --spawn)";
    if (ok(opened)) {
      opened = bus.adopt_fd(fd);
      if (!ok(opened)) err = "cannot use the link: " + bus.last_error();
    }
  }
  if (!ok(opened)) {
    std::fprintf(stderr, "uwbnav hil: %s\n", err.c_str());
    if (child > 0) hil::stop_child(child, 3000);
    return 1;
  }

  hal::CandumpLogWriter rx_log;
  hal::CandumpLogWriter tx_log;
  const uint64_t epoch_offset_us = clock_us(CLOCK_REALTIME) - clock_us(CLOCK_MONOTONIC);
  const std::string ifname = socketcan ? args.get("--can-if") : "can0";
  if (!out.empty() && (!ok(rx_log.open(out + "/can_rx.log", ifname, epoch_offset_us)) ||
                       !ok(tx_log.open(out + "/can_tx.log", ifname, epoch_offset_us)))) {
    std::fprintf(stderr, "uwbnav hil: cannot write logs to %s\n", out.c_str());
    if (child > 0) hil::stop_child(child, 3000);
    return 1;
  }

  hil::RigOptions opt;
  opt.speed = speed;
  opt.align_clock = args.has("--align") || socketcan;
  opt.stop = &g_hil_stop;
  opt.rx_log = out.empty() ? nullptr : &rx_log;
  opt.tx_log = out.empty() ? nullptr : &tx_log;
  opt.progress = stderr;
  std::printf("hil: playing %s (%zu IMU samples, %zu ranges) at speed %.2f\n", rec.name().c_str(), rec.imu.size(),
              rec.uwb.size(), speed);
  std::fflush(stdout);
  hil::RigRun run;
  const Status played = hil::run_rig(rec, bus, opt, run, &err);
  if (ok(played)) out_dir.keep();
  bus.close();
  int child_code = 0;
  if (child > 0) child_code = hil::stop_child(child, 5000);
  if (rx_log.is_open()) ignore_status(rx_log.close());
  if (tx_log.is_open()) ignore_status(tx_log.close());
  if (!ok(played)) {
    std::fprintf(stderr, "uwbnav hil: %s\n", err.c_str());
    return 1;
  }
  if (run.link_closed) std::fprintf(stderr, "uwbnav hil: warning: %s\n", err.c_str());

  hil::HilReport report = hil::build_report(rec, run, !args.has("--no-lockstep"));
  report.link = socketcan ? "can:" + args.get("--can-if") : "unix:" + link;
  if (child > 0 && !out.empty()) report.firmware_latency = firmware_latency_line(out + "/firmware.log");
  hil::print_report(stdout, report);
  if (child > 0) std::printf("hil: firmware stopped with SIGTERM, exit code %d\n", child_code);
  if (!out.empty()) {
    if (!ok(hil::write_report_markdown(out + "/hil_report.md", report))) {
      std::fprintf(stderr, "uwbnav hil: cannot write %s/hil_report.md\n", out.c_str());
      return 1;
    }
    std::printf("outputs: %s/{hil_report.md, can_rx.log, can_tx.log%s}\n", out.c_str(),
                spawn ? ", firmware.log, firmware_can.log" : "");
  }

  // Optional pass/fail checks (CI): each requested check prints its value and bound.
  hil::HilLimits limits;
  if (args.has("--max-missing")) limits.max_missing = static_cast<double>(max_missing);
  if (args.has("--max-latency-ms")) limits.max_latency_ms = max_latency_ms;
  if (args.has("--max-latency-p99-ms")) limits.max_latency_p99_ms = max_latency_p99_ms;
  if (args.has("--max-rmse-m")) limits.max_rmse_m = max_rmse_m;
  int failures = 0;
  for (const auto& line : hil::check_report(report, limits, &failures)) std::printf("%s\n", line.c_str());
  if (child > 0 && child_code != 0) {
    std::printf("CHECK FAILED: firmware exit code %d\n", child_code);
    ++failures;
  }
  if (failures > 0) return 3;
  if (args.has("--max-missing") || args.has("--max-latency-ms") || args.has("--max-latency-p99-ms") ||
      args.has("--max-rmse-m")) {
    std::printf("CHECKS PASSED\n");
  }
  return 0;
}

}  // namespace uwbnav::cli
