// `uwbnav firmware`: the firmware as a real-time host process ("PC board"):
// RealtimeClock + RealtimeLoop drive App::tick every 10 ms; sensors come from
// a recording replayed in real time or from a HIL rig over CAN (docs/hil.md).
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <memory>
#include <string>

#include "firmware/app.hpp"
#include "firmware/realtime_loop.hpp"
#include "hal/host/async_can_log.hpp"
#include "hal/host/async_serial.hpp"
#include "hal/host/candump_log.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/idle_sources.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "hal/host/pty_serial.hpp"
#include "hal/host/realtime_clock.hpp"
#include "hal/host/replay_sources.hpp"
#include "hal/host/socketcan_bus.hpp"
#include "hal/host/stdio_serial.hpp"
#include "tools/cli/args.hpp"
#include "tools/cli/cal_option.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/hil/clock_mapped_sources.hpp"

namespace uwbnav::cli {
namespace {

volatile bool g_stop = false;  // set by SIGINT/SIGTERM, read once per cycle by RealtimeLoop
volatile int g_signal = 0;

void on_signal(int sig) {
  g_signal = sig;
  g_stop = true;
}

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: blocking accept/poll return on a signal
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);
}

uint64_t clock_us(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000U + static_cast<uint64_t>(ts.tv_nsec) / 1000U;
}

// Ends the run when the replayed recording is exhausted or the stdio console's
// input ended (once the console has answered and flushed, at most 2 s later);
// reports a rig that went away.
class RunWatch final : public AppObserver {
 public:
  RunWatch(const hal::ImuSource& imu, const hal::UwbSource& uwb, bool replay, const hal::CanBus& bus, bool link,
           const hal::AsyncSerialPort* stdio, const Console& console)
      : imu_(imu), uwb_(uwb), replay_(replay), bus_(bus), link_(link), stdio_(stdio), console_(console) {}
  void on_range(const RangeReport&) override {}
  void on_output(const NavOutput&) override {
    if (replay_ && imu_.finished() && uwb_.finished()) {
      end_of_recording = true;
      g_stop = true;
    }
    if (stdio_ != nullptr && stdio_->input_closed()) {
      ++cycles_since_eof_;
      idle_cycles_ = console_.busy() ? 0 : idle_cycles_ + 1;
      if (idle_cycles_ >= kIdleCyclesToStop || cycles_since_eof_ >= kMaxCyclesAfterEof) {
        end_of_input = true;
        g_stop = true;
      }
    }
    if (link_ && !link_closed && bus_.state() == hal::CanBusState::kDown) {
      link_closed = true;  // reported after the loop: no terminal I/O inside the cycle
      link_closed_cycle = cycles_;
    }
    ++cycles_;
  }
  bool end_of_recording = false;
  bool end_of_input = false;
  bool link_closed = false;
  uint64_t link_closed_cycle = 0;

 private:
  static constexpr uint32_t kIdleCyclesToStop = 5;      // console idle this long after end of input
  static constexpr uint32_t kMaxCyclesAfterEof = 200;   // 2 s: a stream keeps it busy forever
  const hal::ImuSource& imu_;
  const hal::UwbSource& uwb_;
  bool replay_;
  const hal::CanBus& bus_;
  bool link_;
  const hal::AsyncSerialPort* stdio_;
  const Console& console_;
  uint32_t cycles_since_eof_ = 0;
  uint32_t idle_cycles_ = 0;
  uint64_t cycles_ = 0;
};

// Real-time setup of the loop thread (Linux): memory locked against page
// faults, SCHED_FIFO at `priority`. Each step that is not permitted leaves a
// note and the run goes on without it.
struct RtSetup {
  bool mlocked = false;
  bool fifo = false;
  int priority = 0;
  std::string note;  // what could not be done and why
};

RtSetup setup_realtime(int priority) {
  RtSetup rt;
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    rt.mlocked = true;
  } else {
    rt.note += std::string("mlockall failed (") + std::strerror(errno) +
               ": needs CAP_IPC_LOCK or RLIMIT_MEMLOCK above the process size), page faults can delay cycles; ";
  }
  // Pre-fault the stack the cycle will use, so that its first deep call does not fault.
  volatile uint8_t stack_touch[256 * 1024];
  for (size_t i = 0; i < sizeof stack_touch; i += 4096) stack_touch[i] = 0;
  sched_param sp{};
  sp.sched_priority = priority;
  if (::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &sp) == 0) {
    rt.fifo = true;
    rt.priority = priority;
  } else {
    rt.note += "SCHED_FIFO not permitted (needs CAP_SYS_NICE or an rtprio limit, ulimit -r), running SCHED_OTHER: "
               "other processes' CPU load delays cycles; ";
  }
  if (!rt.note.empty()) rt.note.resize(rt.note.size() - 2);
  return rt;
}

// Pins the calling (loop) thread to `cpu`; the CAN-log writer and console I/O
// threads, started before, keep every CPU. Returns false, with the reason in
// `note`, when the kernel refuses.
bool pin_loop_thread(int cpu, std::string& note) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int rc = ::pthread_setaffinity_np(::pthread_self(), sizeof set, &set);
  if (rc == 0) return true;
  note = "loop thread not pinned to CPU " + std::to_string(cpu) + " (" + std::strerror(rc) + ")";
  return false;
}

// The CPUs this process may run on, as "0-1" or "0,2,5" ("?" when unknown).
std::string allowed_cpus_text(const cpu_set_t& set) {
  std::string out;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (!CPU_ISSET(c, &set)) continue;
    int last = c;
    while (last + 1 < CPU_SETSIZE && CPU_ISSET(last + 1, &set)) ++last;
    if (!out.empty()) out += ",";
    out += std::to_string(c);
    if (last > c) out += "-" + std::to_string(last);
    c = last;
  }
  return out.empty() ? "?" : out;
}

void print_histogram(const LoopStats& l) {
  std::printf("  latency  deadline to end of work: max %u us; cycles per bin:", l.latency_max_us);
  for (uint32_t i = 0; i < kNumLatencyBins; ++i) {
    if (i + 1 < kNumLatencyBins) {
      std::printf(" <=%u:%u", kLatencyBinUpperUs[i], l.latency_hist[i]);
    } else {
      std::printf(" >%u:%u", kLatencyBinUpperUs[kNumLatencyBins - 2], l.latency_hist[i]);
    }
  }
  std::printf("\n");
}

// Waits for the rig to connect to the link (until a signal or the duration).
bool accept_rig(const std::string& path, uint64_t give_up_us, hal::SocketCanBus& bus) {
  int listen_fd = -1;
  std::string err;
  if (!ok(hal::can_link_listen(path, listen_fd, &err))) {
    std::fprintf(stderr, "uwbnav firmware: %s\n", err.c_str());
    return false;
  }
  std::printf("firmware: CAN link listening on %s, waiting for the rig\n", path.c_str());
  std::fflush(stdout);
  int fd = -1;
  Status s = Status::kEmpty;
  while (!g_stop && (give_up_us == 0 || clock_us(CLOCK_MONOTONIC) < give_up_us)) {
    s = hal::can_link_accept(listen_fd, 200, fd, &err);
    if (s != Status::kEmpty) break;
  }
  ::close(listen_fd);
  ::unlink(path.c_str());  // one rig per run: the socket file goes with the listener
  if (!ok(s)) {
    if (!g_stop && s != Status::kEmpty) std::fprintf(stderr, "uwbnav firmware: %s\n", err.c_str());
    return false;
  }
  if (!ok(bus.adopt_fd(fd))) {
    std::fprintf(stderr, "uwbnav firmware: cannot use the link: %s\n", bus.last_error().c_str());
    return false;
  }
  std::printf("firmware: rig connected\n");
  std::fflush(stdout);
  return true;
}

struct RunSummary {
  AppStats stats;
  can::CanTxStats can_tx;
  can::CanSensorStats can_rx;
  hal::CanCounters bus;
  const char* why = "signal";
  double wall_s = 0.0;
  bool logged = false;
  hal::AsyncLogCounters log;
  RtSetup rt;
  bool rt_requested = true;
  int loop_cpu = -1;  // CPU the loop thread is pinned to (--cpu), -1 none
};

void print_summary(const RunSummary& s) {
  const LoopStats& l = s.stats.loop;
  std::printf("firmware: stopped (%s) after %.1f s\n", s.why, s.wall_s);
  std::printf("  loop     cycles %llu  cycle min/avg/max %u/%u/%u us  overruns %llu  jitter max %u us\n",
              static_cast<unsigned long long>(l.cycles), l.cycle_min_us, l.avg_us(), l.cycle_max_us,
              static_cast<unsigned long long>(l.overruns), l.jitter_max_us);
  print_histogram(l);
  if (s.rt_requested) {
    std::printf("  rt       mlockall %s, %s\n", s.rt.mlocked ? "yes" : "no",
                s.rt.fifo ? ("SCHED_FIFO " + std::to_string(s.rt.priority)).c_str() : "SCHED_OTHER");
  } else {
    std::printf("  rt       off (--no-rt): SCHED_OTHER, memory not locked\n");
  }
  if (s.loop_cpu >= 0) std::printf("  cpu      loop thread pinned to CPU %d\n", s.loop_cpu);
  if (s.logged) {
    std::printf("  CAN log  written %llu  overflow %llu  write errors %llu  queue high-water %zu of %zu frames\n",
                static_cast<unsigned long long>(s.log.written), static_cast<unsigned long long>(s.log.overflow),
                static_cast<unsigned long long>(s.log.write_errors), s.log.high_water, s.log.capacity);
  }
  std::printf("  CAN tx   sent %u  dropped %u  failed %u  saturated %u\n", s.can_tx.sent, s.can_tx.dropped,
              s.can_tx.failed, s.can_tx.saturated);
  std::printf("  CAN rx   HIL frames %u  IMU %u  UWB %u  crc %u  counter %u  length %u  lost %u  incomplete %u\n",
              s.can_rx.frames, s.can_rx.imu_samples, s.can_rx.uwb_ranges, s.can_rx.crc_errors,
              s.can_rx.counter_errors, s.can_rx.length_errors, s.can_rx.frames_lost, s.can_rx.incomplete);
  const SourceStats* src[] = {&s.stats.imu, &s.stats.uwb, &s.stats.can_rx};
  const char* names[] = {"imu", "uwb", "can_rx"};
  for (int i = 0; i < 3; ++i) {
    std::printf("  input    %-6s received %u  accepted %u  rejected %u", names[i], src[i]->received, src[i]->accepted,
                src[i]->rejected_total());
    for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
      if (src[i]->rejected[r] > 0) {
        std::printf(" %s=%u", reject_reason_name(static_cast<RejectReason>(r)), src[i]->rejected[r]);
      }
    }
    std::printf("\n");
  }
}

}  // namespace

int cmd_firmware(int argc, char** argv) {
  Args args(argc, argv, {"--no-rt"});
  const std::vector<std::string> known = {"--recording", "--can-link", "--can-if", "--console", "--params",
                                          "--can-log",   "--duration", "--site",   "--param",
                                          "--cal",       "--rt-priority", "--no-rt", "--cpu"};
  const std::string console = args.get("--console", "stdio");
  const char* usage =
      "usage: uwbnav firmware [--recording DIR | --can-link PATH | --can-if NAME] [--site DIR]\n"
      "                       [--console stdio|pty|none] [--params FILE] [--can-log FILE] [--duration S]\n"
      "                       [--param name=value]... [--cal FILE] [--rt-priority 1..99 | --no-rt] [--cpu N]\n"
      "  sensors: --recording DIR replays DIR in real time; without it a HIL rig sends them over CAN\n"
      "  (can.hil_rx_enable = 1) and --site DIR (a recording) gives the anchors and tags\n"
      "  --cal FILE: site range calibration loaded at start (uwbnav calibrate, docs/commissioning.md)\n"
      "  exit status: 0 done, 1 input or start-up failure, 2 usage or parameter error,\n"
      "  3 the recording's IMU or UWB stream ended early (replayed anyway)\n"
      "  real time (docs/realtime.md): memory locked and the loop at SCHED_FIFO --rt-priority (default 80)\n"
      "  when permitted, with a note when not; --no-rt runs without either\n"
      "  --cpu N: the loop thread on CPU N only (one without block-device interrupts, /proc/interrupts);\n"
      "  the CAN-log and console I/O threads keep every CPU\n";
  double duration_s = 0.0;
  if (args.has("--duration")) {
    const std::string text = args.get("--duration");  // keep alive: `end` points into it
    char* end = nullptr;
    duration_s = std::strtod(text.c_str(), &end);
    if (*end != '\0' || !(duration_s > 0.0)) duration_s = -1.0;
  }
  uint64_t rt_priority = 80;
  const bool bad_priority = !args.get_u64("--rt-priority", 80, &rt_priority) || rt_priority < 1 || rt_priority > 99;
  uint64_t loop_cpu = 0;
  const bool bad_cpu = !args.get_u64("--cpu", 0, &loop_cpu) || loop_cpu >= CPU_SETSIZE;
  if (!args.error().empty() || !args.positional().empty() || !args.unknown(known).empty() || duration_s < 0.0 ||
      bad_priority || bad_cpu || (args.has("--no-rt") && args.has("--rt-priority")) ||
      (console != "stdio" && console != "pty" && console != "none") ||
      (args.has("--can-link") && args.has("--can-if"))) {
    std::fprintf(stderr, "%s", usage);
    return 2;
  }
  if (args.has("--cpu")) {
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (::sched_getaffinity(0, sizeof allowed, &allowed) == 0 && !CPU_ISSET(static_cast<int>(loop_cpu), &allowed)) {
      std::fprintf(stderr, "uwbnav firmware: --cpu %llu: not one of the CPUs this process may use (%s)\n",
                   static_cast<unsigned long long>(loop_cpu), allowed_cpus_text(allowed).c_str());
      return 2;
    }
  }
  const bool replay = args.has("--recording");
  const bool link = args.has("--can-link");
  const bool socketcan = args.has("--can-if");
  if (!replay && !link && !socketcan) {
    std::fprintf(stderr, "uwbnav firmware: no sensor input: give --recording DIR, or a CAN bus (--can-link PATH / "
                         "--can-if NAME) on which a HIL rig sends the sensors\n");
    return 2;
  }
  const std::string site_dir = replay ? args.get("--recording") : args.get("--site");
  if (site_dir.empty()) {
    std::fprintf(stderr, "uwbnav firmware: HIL mode needs --site DIR (a recording whose anchors.csv/tags.csv "
                         "describe the site)\n");
    return 2;
  }
  dataset::Recording rec;
  dataset::ReadReport read_report;
  if (!ok(dataset::read_recording(site_dir, rec, read_report))) {
    std::fprintf(stderr, "uwbnav firmware: cannot read %s: %s\n", site_dir.c_str(), read_report.error.c_str());
    return 1;
  }
  // A recording whose streams end early is replayed, but the run says so and exits 3.
  const std::vector<std::string> ended_early = replay ? dataset::streams_ended_early(rec) : std::vector<std::string>{};
  for (const auto& line : ended_early) std::fprintf(stderr, "uwbnav firmware: warning: %s\n", line.c_str());
  if (!replay) {  // the site is all a HIL board takes from the recording
    rec.imu.clear();
    rec.uwb.clear();
  }
  if (!apply_cal_option(args, rec.site, "uwbnav firmware")) return 1;
  std::vector<std::pair<std::string, float>> overrides;
  if (!parse_param_options(args, "uwbnav firmware", &overrides)) return 2;

  install_signal_handlers();
  const uint64_t t_start_mono_us = clock_us(CLOCK_MONOTONIC);
  const uint64_t give_up_us = duration_s > 0.0 ? t_start_mono_us + static_cast<uint64_t>(duration_s * 1e6) : 0;
  RunSummary summary;
  {
    // Board clock = CLOCK_MONOTONIC [us], so a rig on the same host stamps samples in the firmware's time base.
    hal::RealtimeClock clock(clock_us(CLOCK_MONOTONIC));

    // CAN bus: SocketCAN interface, link to a rig, or an in-memory bus (log only).
    hal::SocketCanBus sock_bus;
    hal::MemCanBus mem_bus(64, 1024, 16);
    hal::CanBus* bus = &mem_bus;
    if (socketcan) {
      const std::string ifname = args.get("--can-if");
      if (!ok(sock_bus.open(ifname))) {
        std::fprintf(stderr, "uwbnav firmware: cannot open CAN interface %s: %s\n", ifname.c_str(),
                     sock_bus.last_error().c_str());
        return 1;
      }
      bus = &sock_bus;
    } else if (link) {
      if (!accept_rig(args.get("--can-link"), give_up_us, sock_bus)) return g_stop ? 0 : 1;
      bus = &sock_bus;
    }
    hal::CandumpLogWriter can_log;
    std::unique_ptr<hal::AsyncCanLog> tee;  // frames leave the cycle through a bounded queue
    if (args.has("--can-log")) {
      const uint64_t epoch_offset_us = clock_us(CLOCK_REALTIME) - clock_us(CLOCK_MONOTONIC);
      const std::string ifname = socketcan ? args.get("--can-if") : "can0";
      if (!ok(can_log.open(args.get("--can-log"), ifname, epoch_offset_us))) {
        std::fprintf(stderr, "uwbnav firmware: cannot write %s\n", args.get("--can-log").c_str());
        return 1;
      }
      tee = std::make_unique<hal::AsyncCanLog>(*bus, can_log, true);
      tee->start();  // before the loop thread turns SCHED_FIFO: the writer stays SCHED_OTHER
      bus = tee.get();
    }

    // Serial console.
    hal::NullSerialPort null_serial;
    std::unique_ptr<hal::StdioSerialPort> stdio_serial;
    hal::PtySerialPort pty_serial;
    hal::SerialPort* serial = &null_serial;
    if (console == "stdio") {
      stdio_serial = std::make_unique<hal::StdioSerialPort>();
      serial = stdio_serial.get();
      if (stdio_serial->raw_terminal()) {
        std::printf("firmware: console on this terminal (raw: Ctrl-C drops the line, Ctrl-D ends the session)\n");
      }
    } else if (console == "pty") {
      std::string err;
      if (!ok(pty_serial.open(&err))) {
        std::fprintf(stderr, "uwbnav firmware: cannot open a pty: %s\n", err.c_str());
        return 1;
      }
      std::printf("firmware: console on %s (e.g. picocom %s)\n", pty_serial.slave_name().c_str(),
                  pty_serial.slave_name().c_str());
      std::fflush(stdout);
      serial = &pty_serial;
    }

    // Terminal/pipe I/O leaves the cycle: the console talks to bounded rings that
    // an I/O thread (SCHED_OTHER, started before the loop turns SCHED_FIFO) moves.
    std::unique_ptr<hal::AsyncSerialPort> async_serial;
    if (serial != &null_serial) {
      hal::StdioSerialPort* stdio_port = stdio_serial.get();
      std::function<bool()> closed;
      if (stdio_port != nullptr) closed = [stdio_port] { return stdio_port->input_closed(); };
      async_serial = std::make_unique<hal::AsyncSerialPort>(*serial, std::move(closed));
      async_serial->start();
      serial = async_serial.get();
    }

    // Parameters.
    hal::EmptyParamStore no_store;
    std::unique_ptr<hal::FileParamStore> file_store;
    hal::ParamStore* store = &no_store;
    if (args.has("--params")) {
      file_store = std::make_unique<hal::FileParamStore>(args.get("--params"));
      store = file_store.get();
    }

    // Sensors: the recording mapped onto the clock (first sample 100 ms from now), or nothing (HIL over CAN).
    hal::ReplaySources replay_sources(rec);
    const hil::TimeMap map = hil::map_recording_to_clock(rec, clock.now_us() + 100000, 1.0);
    hil::ClockMappedImuSource mapped_imu(replay_sources.imu, map);
    hil::ClockMappedUwbSource mapped_uwb(replay_sources.uwb, map);
    hil::ClockMappedGnssSource mapped_gnss(replay_sources.gnss, map);
    hil::ClockMappedNeighbourSource mapped_neighbours(replay_sources.neighbours, map);
    hal::IdleImuSource no_imu;
    hal::IdleUwbSource no_uwb;
    hal::ImuSource& imu = replay ? static_cast<hal::ImuSource&>(mapped_imu) : no_imu;
    hal::UwbSource& uwb = replay ? static_cast<hal::UwbSource&>(mapped_uwb) : no_uwb;

    hal::Board board{imu, uwb, *bus, *serial, clock, *store, rec.site,
                     replay && !rec.gnss.empty() ? &mapped_gnss : nullptr,
                     replay && !rec.neighbours.empty() ? &mapped_neighbours : nullptr};
    auto app = std::make_unique<App>(board);
    if (!ok(app->init())) {
      std::fprintf(stderr, "uwbnav firmware: the firmware rejected the site of %s (anchors/tags or range calibration)\n",
                   site_dir.c_str());
      return 1;
    }
    for (const auto& [name, value] : overrides) {
      const ParamDef* d = Params::find(name.c_str());  // checked by parse_param_options
      if (d == nullptr || !ok(app->set_param(d->index, value))) {
        std::fprintf(stderr, "uwbnav firmware: param: %s refused by the firmware\n", name.c_str());
        return 2;
      }
    }
    if (!replay && !ok(app->set_param(ParamId::kCanHilRxEnable, 1.0F))) return 1;

    RunWatch watch(imu, uwb, replay, *bus, link, stdio_serial != nullptr ? async_serial.get() : nullptr,
                   app->console());
    app->set_observer(&watch);
    std::printf("firmware: running (%s sensors, CAN %s%s), stop with Ctrl-C%s\n",
                replay ? "recording" : "HIL CAN",
                socketcan ? args.get("--can-if").c_str() : (link ? "link" : "in memory"),
                args.has("--can-log") ? ", logged" : "",
                stdio_serial != nullptr ? " (outside a raw terminal) or end of console input" : "");
    std::fflush(stdout);
    summary.rt_requested = !args.has("--no-rt");
    if (summary.rt_requested) {
      summary.rt = setup_realtime(static_cast<int>(rt_priority));
      std::printf("firmware: real time: memory %s, %s\n", summary.rt.mlocked ? "locked" : "not locked",
                  summary.rt.fifo ? ("SCHED_FIFO priority " + std::to_string(summary.rt.priority)).c_str()
                                  : "SCHED_OTHER");
      if (!summary.rt.note.empty()) std::printf("firmware: note: %s\n", summary.rt.note.c_str());
      std::fflush(stdout);
    }
    if (args.has("--cpu")) {
      std::string note;
      if (pin_loop_thread(static_cast<int>(loop_cpu), note)) {
        summary.loop_cpu = static_cast<int>(loop_cpu);
        std::printf("firmware: loop thread pinned to CPU %d\n", summary.loop_cpu);
      } else {
        std::printf("firmware: note: %s\n", note.c_str());
      }
      std::fflush(stdout);
    }
    RealtimeLoop loop(*app, clock);
    const uint64_t now_us = clock_us(CLOCK_MONOTONIC);
    uint64_t max_cycles = 0;
    if (give_up_us != 0) max_cycles = give_up_us > now_us ? (give_up_us - now_us) / kCyclePeriodUs : 1;
    loop.run(g_stop, max_cycles);

    summary.stats = app->stats();
    summary.can_tx = app->can_tx_stats();
    summary.can_rx = app->can_rx_stats();
    summary.bus = bus->counters();
    summary.why = g_signal != 0 ? (g_signal == SIGINT ? "SIGINT" : "SIGTERM")
                                : (watch.end_of_recording ? "end of recording"
                                                          : (watch.end_of_input ? "end of console input" : "duration"));
    if (async_serial != nullptr) async_serial->stop();  // the console's last output goes out
    if (tee != nullptr) {
      tee->stop();  // drains the queue into the log
      summary.logged = true;
      summary.log = tee->log_counters();
    }
    if (can_log.is_open()) ignore_status(can_log.close());
    if (watch.link_closed) {
      std::fprintf(stderr, "firmware: CAN link closed by the peer at cycle %llu; ran on until stopped\n",
                   static_cast<unsigned long long>(watch.link_closed_cycle));
    }
  }
  summary.wall_s = static_cast<double>(clock_us(CLOCK_MONOTONIC) - t_start_mono_us) * 1e-6;
  if (console == "stdio") std::printf("\n");  // end the console's prompt line
  print_summary(summary);
  for (const auto& line : ended_early) std::fprintf(stderr, "uwbnav firmware: %s\n", line.c_str());
  return ended_early.empty() ? 0 : 3;
}

}  // namespace uwbnav::cli
