// Console commands: help, version, status, stats, anchors, ekf, param, log,
// stream, reset, history, echo, cal. Reply format: docs/console.md.
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "estimator/nlos/svm_model.hpp"
#include "estimator/params.hpp"
#include "firmware/app.hpp"
#include "firmware/console/console.hpp"
#include "firmware/param_text.hpp"
#include "firmware/text_format.hpp"

#ifndef UWBNAV_VERSION
#define UWBNAV_VERSION "unknown"
#endif
#ifndef UWBNAV_GIT_HASH
#define UWBNAV_GIT_HASH "unknown"
#endif

namespace uwbnav {
namespace {

constexpr float kRadToDeg = 57.2957795F;

unsigned long ul(uint32_t v) { return static_cast<unsigned long>(v); }

const char* can_state_name(hal::CanBusState s) {
  switch (s) {
    case hal::CanBusState::kErrorActive: return "error_active";
    case hal::CanBusState::kErrorPassive: return "error_passive";
    case hal::CanBusState::kBusOff: return "bus_off";
    case hal::CanBusState::kDown: return "down";
  }
  return "unknown";
}

uint32_t crc_bytes(uint32_t crc, uint32_t v, size_t n) {
  uint8_t b[4];
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>(v >> (8U * i));
  return crc32_update(crc, b, n);
}

uint32_t crc_float(uint32_t crc, float f) {
  uint32_t bits = 0;
  std::memcpy(&bits, &f, sizeof bits);
  return crc_bytes(crc, bits, 4);
}

// CRC-32 of the parameter table layout (stable ids, names, defaults, bounds):
// two builds with the same checksum read a parameter store the same way.
uint32_t params_table_crc32() {
  uint32_t crc = 0;
  for (const ParamDef& p : kParamDefs) {
    crc = crc_bytes(crc, p.stable_id, 2);
    crc = crc32_update(crc, reinterpret_cast<const uint8_t*>(p.name), std::strlen(p.name));
    crc = crc_float(crc, p.def);
    crc = crc_float(crc, p.min);
    crc = crc_float(crc, p.max);
  }
  return crc;
}

bool parse_rate(const char* text, uint32_t* out) {
  if (std::strcmp(text, "off") == 0) {
    *out = 0;
    return true;
  }
  char* endp = nullptr;
  const unsigned long v = std::strtoul(text, &endp, 10);
  if (endp == text || *endp != '\0' || text[0] == '-' || v > Console::kMaxStreamRateHz) return false;
  *out = static_cast<uint32_t>(v);
  return true;
}

constexpr const char* kStreamNames[] = {"pos", "stats", "anchors"};
static_assert(sizeof kStreamNames / sizeof kStreamNames[0] == static_cast<size_t>(StreamKind::kCount),
              "one name per stream");

}  // namespace

constexpr const char* kParamUsage = "param list [-c] [GLOB]|get NAME|set NAME VALUE|save|load|reset [NAME]";

const Console::Command Console::kCommands[] = {
    {"help", "help", "this list", &Console::cmd_help},
    {"version", "version", "firmware version, git hash, parameter table and NLOS model checksums",
     &Console::cmd_version},
    {"status", "status", "mode, position +- 1-sigma, time since last IMU/UWB, ranges used", &Console::cmd_status},
    {"stats", "stats", "loop timing, frames and rejects per source, CAN, estimator, console counters",
     &Console::cmd_stats},
    {"anchors", "anchors", "per anchor: last range, innovation, NLOS probability, LOS/NLOS counts, state",
     &Console::cmd_anchors},
    {"ekf", "ekf [-v]", "state vector and covariance diagonal (-v: full 15x15 covariance)", &Console::cmd_ekf},
    {"param", kParamUsage,
     "parameters (bounds-checked, applied live; save/load: parameter store)", &Console::cmd_param},
    {"log", "log level [error|warn|info|debug]", "show or set the log level (param console.log_level)",
     &Console::cmd_log},
    {"stream", "stream [pos|stats|anchors RATE_HZ|off]", "periodic machine-readable lines ($pos, $stats, $anchor)",
     &Console::cmd_stream},
    {"reset", "reset filter|stats", "restart the estimator, or zero the counters", &Console::cmd_reset},
    {"history", "history", "recent lines; !! repeats the last, !N repeats entry N", &Console::cmd_history},
    {"echo", "echo [on|off]", "echo of typed characters and the prompt", &Console::cmd_echo},
    {"cal", "cal", "site range calibration: per anchor/tag pair offset and sigma, or uncalibrated", &Console::cmd_cal},
};
const size_t Console::kNumCommands = sizeof Console::kCommands / sizeof Console::kCommands[0];

void Console::banner() {
  begin("console");
  add(" ready fw=%s git=%s (type help)", UWBNAV_VERSION, UWBNAV_GIT_HASH);
  reply_end();
  prompt();
}

void Console::cmd_help(size_t argc, char**) {
  if (argc != 1) {
    error("help: takes no arguments");
    return;
  }
  start_job(Job::kHelp, false);
}

bool Console::step_help(size_t step) {
  if (step >= kNumCommands) return false;
  begin("help ");
  add("%-58s %s", kCommands[step].usage, kCommands[step].summary);
  reply_end();
  return step + 1 < kNumCommands;
}

void Console::cmd_version(size_t argc, char**) {
  if (argc != 1) {
    error("version: takes no arguments");
    return;
  }
  begin("version");
  add(" fw=%s git=%s params=%lu params_crc=0x%08lx svm1_crc=0x%08lx svm2_crc=0x%08lx", UWBNAV_VERSION,
      UWBNAV_GIT_HASH, static_cast<unsigned long>(kNumParams), static_cast<unsigned long>(params_table_crc32()),
      ul(kSvmModelRangeRate.crc32), ul(kSvmModelRangeRateSpeed.crc32));
  reply_end();
}

void Console::add_pos_fields() {
  const NavOutput& o = app_.last_output();
  const float speed_mps = std::sqrt(o.vel_nav_mps.x * o.vel_nav_mps.x + o.vel_nav_mps.y * o.vel_nav_mps.y);
  // In float (no soft double on the board): the 0.1 deg text can differ from
  // that of the double product when both lie within 1e-5 deg of a rounding
  // boundary (1 line in 160,000 of a replayed drive).
  const float heading_deg = o.heading_rad * kRadToDeg;
  add_u64(" t_us=", o.t_us);
  add(" mode=%s", nav_status_name(o.status));
  add_fixed(" x_m=", o.pos_nav_m.x, 3);
  add_fixed(" y_m=", o.pos_nav_m.y, 3);
  add_fixed(" z_m=", o.pos_nav_m.z, 3);
  add_fixed(" sx_m=", o.pos_sigma_m.x, 3);
  add_fixed(" sy_m=", o.pos_sigma_m.y, 3);
  add_fixed(" sz_m=", o.pos_sigma_m.z, 3);
  add_fixed(" speed_mps=", speed_mps, 2);
  add_fixed(" heading_deg=", heading_deg, 1);
  add(" used=%u rejected=%u", static_cast<unsigned>(o.ranges_used), static_cast<unsigned>(o.ranges_rejected));
}

void Console::cmd_status(size_t argc, char**) {
  if (argc != 1) {
    error("status: takes no arguments");
    return;
  }
  const NavDiagnostics dg = app_.nav_counters();
  const NavDiagnostics& raw = app_.navigator().diagnostics();  // times are not counters
  const uint64_t now = app_.last_tick_us();
  begin("status");
  add_pos_fields();
  if (raw.last_imu_t_us == 0 || raw.last_imu_t_us > now) {
    add(" imu_age_ms=none");
  } else {
    add_u64(" imu_age_ms=", (now - raw.last_imu_t_us) / 1000U);
  }
  if (raw.last_range_used_t_us == 0 || raw.last_range_used_t_us > now) {
    add(" uwb_age_ms=none");
  } else {
    add_u64(" uwb_age_ms=", (now - raw.last_range_used_t_us) / 1000U);
  }
  add(" used_total=%lu", ul(dg.ranges_used));
  add_reset_fields(dg);
  reply_end();
}

// Every kind of reset and recovery, since start or `reset stats`: hard resets
// (non-finite or exploded state), operator resets (`reset filter`), and the
// recovery ladder (inflations, re-anchors, re-alignments), and what climbed it:
// integrity failures and short-range failures.
void Console::add_reset_fields(const NavDiagnostics& dg) {
  add(" resets=%lu operator_resets=%lu inflations=%lu reanchors=%lu reinits=%lu integrity_fails=%lu short_fails=%lu",
      ul(dg.resets), ul(dg.operator_resets), ul(dg.inflations), ul(dg.reanchors), ul(dg.reinits),
      ul(dg.integrity_fails), ul(dg.short_range_fails));
}

void Console::cmd_stats(size_t argc, char**) {
  if (argc != 1) {
    error("stats: takes no arguments");
    return;
  }
  start_job(Job::kStats, false);
}

bool Console::step_stats(size_t step) {
  const AppStats& s = snap_.part.stats.app;
  // Lines 7-8 (GNSS) and 9-10 (neighbours) exist only in builds with those features.
  if (!UWBNAV_GNSS && step >= 7) step += 2;
  if (!UWBNAV_COOP && step >= 9) step += 2;
  switch (step) {
    case 0: {
      const LoopStats& l = s.loop;
      begin("stats loop");
      add_u64(" cycles=", l.cycles);
      add_u64(" overruns=", l.overruns);
      add(" cycle_min_us=%lu cycle_avg_us=%lu cycle_max_us=%lu jitter_max_us=%lu", ul(l.cycle_min_us), ul(l.avg_us()),
          ul(l.cycle_max_us), ul(l.jitter_max_us));
      break;
    }
    case 1: {
      // Cycle latency (deadline to end of work) histogram: counts per bin "le<upper_us>", then "gt<last>".
      begin("stats latency");
#if UWBNAV_LOOP_HISTOGRAM
      const LoopStats& l = s.loop;
      add(" max_us=%lu", ul(l.latency_max_us));
      for (uint32_t i = 0; i + 1 < kNumLatencyBins; ++i) add(" le%lu=%lu", ul(kLatencyBinUpperUs[i]), ul(l.latency_hist[i]));
      add(" gt%lu=%lu", ul(kLatencyBinUpperUs[kNumLatencyBins - 2]), ul(l.latency_hist[kNumLatencyBins - 1]));
#endif
      break;
    }
    case 2:
    case 3:
    case 4: {
      const SourceStats& src = step == 2 ? s.imu : (step == 3 ? s.uwb : s.can_rx);
      begin("stats src=");
      add("%s received=%lu accepted=%lu io_errors=%lu", step == 2 ? "imu" : (step == 3 ? "uwb" : "can_rx"),
          ul(src.received), ul(src.accepted), ul(src.io_errors));
      for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
        add(" %s=%lu", reject_reason_name(static_cast<RejectReason>(r)), ul(src.rejected[r]));
      }
      break;
    }
    case 5: {
      const hal::CanCounters& c = snap_.part.stats.can;
      begin("stats can");
      add(" state=%s tx_ok=%lu tx_dropped=%lu bus_off=%lu rx_ok=%lu rx_overflow=%lu error_frames=%lu",
          can_state_name(snap_.part.stats.can_state), ul(c.tx_ok), ul(c.tx_dropped), ul(c.bus_off), ul(c.rx_ok),
          ul(c.rx_overflow), ul(c.error_frames));
      break;
    }
    case 6: {
      const NavDiagnostics& dg = snap_.part.stats.nav;
      begin("stats nav");
      add(" imu_samples=%lu ranges_received=%lu ranges_used=%lu ranges_rejected=%lu", ul(dg.imu_samples),
          ul(dg.ranges_received), ul(dg.ranges_used), ul(dg.ranges_rejected));
      add_reset_fields(dg);
      add(" iterated_updates=%lu", ul(dg.iterated_updates));
      // What the estimator learned on line (docs/ekf.md): the LOS ranging
      // 1-sigma and the gains on the gyro and accelerometer bias random walks.
      add_fixed(" uwb_sigma_m=", dg.uwb_sigma_m, 3);
      const float rw_gain[2] = {dg.gyro_bias_rw_gain, dg.accel_bias_rw_gain};
      add_fixed(" bias_rw_gain=", rw_gain, 2, 2);
      break;
    }
#if UWBNAV_GNSS
    case 7: {
      const SourceStats& src = s.gnss;
      begin("stats src=");
      add("gnss received=%lu accepted=%lu io_errors=%lu", ul(src.received), ul(src.accepted), ul(src.io_errors));
      for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
        add(" %s=%lu", reject_reason_name(static_cast<RejectReason>(r)), ul(src.rejected[r]));
      }
      break;
    }
    case 8: {
      // What the estimator did with the accepted fixes, per GnssVerdict.
      const NavDiagnostics& dg = snap_.part.stats.nav;
      begin("stats gnss");
      add(" received=%lu fused=%lu", ul(dg.gnss_received), ul(dg.gnss_used));
      for (uint32_t v = 1; v < static_cast<uint32_t>(GnssVerdict::kCount); ++v) {
        add(" %s=%lu", gnss_verdict_name(static_cast<GnssVerdict>(v)), ul(dg.gnss_rejected[v]));
      }
      break;
    }
#endif
#if UWBNAV_COOP
    case 9: {
      const SourceStats& src = s.neighbours;
      begin("stats src=");
      add("neighbours received=%lu accepted=%lu io_errors=%lu", ul(src.received), ul(src.accepted),
          ul(src.io_errors));
      for (uint32_t r = 0; r < kNumRejectReasons; ++r) {
        add(" %s=%lu", reject_reason_name(static_cast<RejectReason>(r)), ul(src.rejected[r]));
      }
      break;
    }
    case 10: {
      // What the estimator did with the ranges to neighbour vehicles, per NeighbourVerdict.
      const NavDiagnostics& dg = snap_.part.stats.nav;
      begin("stats coop");
      add(" states=%lu evictions=%lu ranges=%lu fused=%lu", ul(dg.neighbour_states), ul(dg.neighbour_evictions),
          ul(dg.neighbour_ranges), ul(dg.neighbour_used));
      for (uint32_t v = 1; v < static_cast<uint32_t>(NeighbourVerdict::kCount); ++v) {
        add(" %s=%lu", neighbour_verdict_name(static_cast<NeighbourVerdict>(v)), ul(dg.neighbour_rejected[v]));
      }
      break;
    }
#endif
    default: {
      const LogCounters& lc = logger().counters();
      begin("stats console");
      add_u64(" rx_bytes=", stats_.rx_bytes);
      add_u64(" tx_bytes=", stats_.tx_bytes);
      add_u64(" dropped_bytes=", stats_.dropped_bytes);
      add(" lines=%lu commands=%lu errors=%lu overlong=%lu garbage=%lu max_rx_per_tick=%lu max_tx_per_tick=%lu"
          " log_emitted=%lu log_suppressed=%lu",
          ul(stats_.lines), ul(stats_.commands), ul(stats_.errors), ul(stats_.overlong_lines), ul(stats_.garbage_lines),
          ul(stats_.max_rx_per_poll), ul(stats_.max_tx_per_poll), ul(lc.emitted), ul(lc.suppressed));
      reply_end();
      return false;
    }
  }
  reply_end();
  return true;
}

void Console::cmd_anchors(size_t argc, char**) {
  if (argc != 1) {
    error("anchors: takes no arguments");
    return;
  }
  start_job(Job::kAnchors, false);
}

bool Console::step_anchors(size_t step) {
  const size_t n = snap_.part.anchors.num_anchors;
  if (step == 0) {
    begin("anchors");
    add(" count=%lu", static_cast<unsigned long>(n));
    reply_end();
    return n > 0;
  }
  const AnchorStatus& a = snap_.part.anchors.anchors[step - 1];
  const uint64_t now = snap_.t_us;
  begin("anchors");
  add_anchor_fields(a);
  if (a.last_t_us == 0 || a.last_t_us > now) {
    add(" age_ms=none");
  } else {
    add_u64(" age_ms=", (now - a.last_t_us) / 1000U);
  }
  reply_end();
  return step < n;
}

// "id state range_m innov_m p_nlos los nlos used" of `anchors` and `$anchor`.
void Console::add_anchor_fields(const AnchorStatus& a) {
  add(" id=%u state=%s", static_cast<unsigned>(a.anchor_id), a.nlos_state ? "nlos" : "los");
  add_fixed(" range_m=", a.last_range_m, 3);
  add_fixed(" innov_m=", a.last_innovation_m, 3);
  add_fixed(" p_nlos=", a.last_p_nlos, 3);
  add(" los=%lu nlos=%lu used=%lu", ul(a.los_count), ul(a.nlos_count), ul(a.used_count));
}

void Console::stream_anchor_lines() {
  const Navigator& nav = app_.navigator();
  for (size_t i = 0; i < nav.num_anchors(); ++i) {
    const AnchorStatus& a = nav.anchor_status(i);
    begin_async("$anchor");
    add_u64(" t_us=", now_us_);
    add_anchor_fields(a);
    end_async();
  }
}

void Console::cmd_ekf(size_t argc, char** argv) {
  const bool verbose = argc == 2 && std::strcmp(argv[1], "-v") == 0;
  if (argc > 2 || (argc == 2 && !verbose)) {
    error("ekf: usage: ekf [-v]");
    return;
  }
  start_job(Job::kEkf, verbose);
}

bool Console::step_ekf(size_t step) {
  constexpr size_t kStates = Navigator::kErrorStateSize;
  if (step == 0) {
    const float* x = snap_.part.ekf.state;
    begin("ekf state");
    add_fixed(" p_m=", x, 3, 3);
    add_fixed(" v_mps=", x + 3, 3, 3);
    add_fixed(" q=", x + 6, 4, 5);
    add_fixed(" ba_mps2=", x + 10, 3, 4);
    add_fixed(" bg_radps=", x + 13, 3, 5);
    reply_end();
    return true;
  }
  if (step == 1) {
    float p[kStates];
    for (size_t i = 0; i < kStates; ++i) p[i] = snap_.part.ekf.cov[i][i];
    begin("ekf pdiag");
    add_general(" p_m2=", p, 3, 3);
    add_general(" v_m2ps2=", p + 3, 3, 3);
    add_general(" att_rad2=", p + 6, 3, 3);
    add_general(" ba_m2ps4=", p + 9, 3, 3);
    add_general(" bg_rad2ps2=", p + 12, 3, 3);
    reply_end();
    return job_verbose_;
  }
  const size_t row = step - 2;
  begin("ekf cov");
  add(" row=%lu", static_cast<unsigned long>(row));
  add_general(" v=", snap_.part.ekf.cov[row], kStates, 3);
  reply_end();
  return row + 1 < kStates;
}

void Console::add_param(size_t index, bool with_doc) {
  const ParamDef& p = kParamDefs[index];
  add(" name=%s", p.name);
  add_general(" value=", app_.params().get(p.index));
  add_general(" default=", p.def);
  add_general(" min=", p.min);
  add_general(" max=", p.max);
  add(" unit=%s", p.unit);
  if (with_doc && p.doc[0] != '\0') add(" doc=\"%s\"", p.doc);
}

// Reply of param set / param reset NAME: "param name=.. value=.. old=..".
void Console::add_param_change(const ParamDef& p, float old) {
  begin("param");
  add(" name=%s", p.name);
  add_general(" value=", app_.params().get(p.index));
  add_general(" old=", old);
  reply_end();
}

namespace {

// Shell-style glob: '*' any run of characters, '?' one character, others literal.
bool glob_match(const char* pattern, const char* text) {
  const char* star = nullptr;  // last '*' seen in the pattern
  const char* resume = text;   // where the text resumes after that '*'
  while (*text != '\0') {
    if (*pattern == '*') {
      star = pattern++;
      resume = text;
    } else if (*pattern == '?' || *pattern == *text) {
      ++pattern;
      ++text;
    } else if (star != nullptr) {
      pattern = star + 1;
      text = ++resume;
    } else {
      return false;
    }
  }
  while (*pattern == '*') ++pattern;
  return *pattern == '\0';
}

}  // namespace

bool Console::param_listed(size_t index) const {
  const ParamDef& p = kParamDefs[index];
  if (list_changed_only_ && app_.params().get(p.index) == p.def) return false;
  return list_glob_[0] == '\0' || glob_match(list_glob_, p.name);
}

size_t Console::next_listed(size_t from) const {
  while (from < kNumParams && !param_listed(from)) ++from;
  return from;
}

// `param list [-c] [GLOB]`: a count line, then one line per listed parameter.
bool Console::step_param_list(size_t step) {
  begin("param");
  if (step == 0) {
    size_t n = 0;
    for (size_t i = next_listed(0); i < kNumParams; i = next_listed(i + 1)) ++n;
    add(" count=%lu", static_cast<unsigned long>(n));
    list_cursor_ = next_listed(0);
  } else {
    add_param(list_cursor_, false);
    list_cursor_ = next_listed(list_cursor_ + 1);
  }
  reply_end();
  return list_cursor_ < kNumParams;
}

void Console::cmd_param(size_t argc, char** argv) {
  const char* sub = argc >= 2 ? argv[1] : "";
  if (argc >= 2 && argc <= 4 && std::strcmp(sub, "list") == 0) {
    bool changed_only = false;
    const char* glob = "";
    for (size_t i = 2; i < argc; ++i) {
      if (std::strcmp(argv[i], "-c") == 0 && !changed_only) {
        changed_only = true;
      } else if (glob[0] == '\0' && argv[i][0] != '-' && std::strlen(argv[i]) < sizeof list_glob_) {
        glob = argv[i];
      } else {
        error("param: usage: %s", kParamUsage);
        return;
      }
    }
    list_changed_only_ = changed_only;
    std::strcpy(list_glob_, glob);
    start_job(Job::kParamList, false);
    return;
  }
  if (argc == 3 && std::strcmp(sub, "get") == 0) {
    const ParamDef* p = Params::find(argv[2]);
    if (p == nullptr) {
      error("param: unknown parameter '%s' (see param list)", argv[2]);
      return;
    }
    begin("param");
    add_param(static_cast<size_t>(p->index), true);
    reply_end();
    return;
  }
  if (argc == 4 && std::strcmp(sub, "set") == 0) {
    const ParamDef* p = nullptr;
    float v = 0.0F;
    char why[kParamErrorMax];
    if (!ok(parse_param_value(argv[2], argv[3], &p, &v, why, sizeof why))) {
      error("param: %s; unchanged", why);
      return;
    }
    const float old = app_.params().get(p->index);
    const Status s = app_.set_param(p->index, v);
    if (!ok(s)) {
      error("param: set %s failed (%s); unchanged", p->name, status_name(s));
      return;
    }
    char old_text[kGeneralTextMax];
    char new_text[kGeneralTextMax];
    (void)format_general(old_text, sizeof old_text, old, kGeneralPrecision);
    (void)format_general(new_text, sizeof new_text, v, kGeneralPrecision);
    UWBNAV_LOG_INFO("console", "param %s %s -> %s", p->name, old_text, new_text);
    add_param_change(*p, old);
    return;
  }
  if (argc == 2 && (std::strcmp(sub, "save") == 0 || std::strcmp(sub, "load") == 0)) {
    const bool save = sub[0] == 's';
    const Status s = save ? app_.save_params() : app_.load_params();
    if (!ok(s)) {
      error("param: %s failed (%s)%s", sub, status_name(s), save ? "" : "; values unchanged");
      return;
    }
    begin("param");
    add(" %s=ok count=%lu", save ? "saved" : "loaded", static_cast<unsigned long>(kNumParams));
    reply_end();
    return;
  }
  if ((argc == 2 || argc == 3) && std::strcmp(sub, "reset") == 0) {
    if (argc == 2) {
      Params defaults;
      app_.apply_params(defaults);
      begin("param");
      add(" reset=all count=%lu", static_cast<unsigned long>(kNumParams));
      reply_end();
      return;
    }
    const ParamDef* p = Params::find(argv[2]);
    if (p == nullptr) {
      error("param: unknown parameter '%s' (see param list)", argv[2]);
      return;
    }
    const float old = app_.params().get(p->index);
    ignore_status(app_.set_param(p->index, p->def));  // the default is inside [min, max] (static_assert)
    add_param_change(*p, old);
    return;
  }
  error("param: usage: %s", kParamUsage);
}

void Console::cmd_log(size_t argc, char** argv) {
  if (argc < 2 || argc > 3 || std::strcmp(argv[1], "level") != 0) {
    error("log: usage: log level [error|warn|info|debug]");
    return;
  }
  if (argc == 3) {
    LogLevel l = LogLevel::kInfo;
    if (!parse_log_level(argv[2], &l)) {
      error("log: unknown level '%s' (error|warn|info|debug)", argv[2]);
      return;
    }
    ignore_status(app_.set_param(ParamId::kConsoleLogLevel, static_cast<float>(static_cast<uint8_t>(l))));
    apply_log_params();
  }
  const LogCounters& lc = logger().counters();
  begin("log");
  add(" level=%s", log_level_name(logger().level()));
  add_general(" rate_per_s=", app_.params().get(ParamId::kConsoleLogRate));
  add(" emitted=%lu suppressed=%lu", ul(lc.emitted), ul(lc.suppressed));
  reply_end();
}

void Console::cmd_stream(size_t argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "off") == 0) {
    for (uint32_t& r : stream_rate_hz_) r = 0;
  } else if (argc == 3) {
    size_t k = 0;
    while (k < static_cast<size_t>(StreamKind::kCount) && std::strcmp(argv[1], kStreamNames[k]) != 0) ++k;
    if (k == static_cast<size_t>(StreamKind::kCount)) {
      error("stream: unknown stream '%s' (pos|stats|anchors)", argv[1]);
      return;
    }
    uint32_t rate = 0;
    if (!parse_rate(argv[2], &rate)) {
      error("stream: rate '%s' not in 0..%lu Hz (or off)", argv[2], ul(kMaxStreamRateHz));
      return;
    }
    stream_rate_hz_[k] = rate;
    stream_next_us_[k] = now_us_;
  } else if (argc != 1) {
    error("stream: usage: stream [pos|stats|anchors RATE_HZ|off]");
    return;
  }
  begin("stream");
  for (size_t k = 0; k < static_cast<size_t>(StreamKind::kCount); ++k) {
    add(" %s_hz=%lu", kStreamNames[k], ul(stream_rate_hz_[k]));
  }
  reply_end();
}

void Console::cmd_reset(size_t argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "filter") == 0) {
    app_.reset_filter();
    UWBNAV_LOG_INFO("console", "filter reset by operator");
    begin("reset filter=ok");
    reply_end();
    return;
  }
  if (argc == 2 && std::strcmp(argv[1], "stats") == 0) {
    app_.reset_stats();
    reset_stats();
    logger().reset_counters();
    begin("reset stats=ok");
    reply_end();
    return;
  }
  error("reset: usage: reset filter|stats");
}

void Console::cmd_history(size_t argc, char**) {
  if (argc != 1) {
    error("history: takes no arguments");
    return;
  }
  start_job(Job::kHistory, false);
}

bool Console::step_history(size_t step) {
  const uint32_t newest = editor_.history_newest();
  const uint32_t oldest = editor_.history_oldest();
  if (step == 0) {
    begin("history");
    add(" count=%lu", ul(newest == 0 ? 0 : newest - oldest + 1));
    reply_end();
    return newest > 0;
  }
  const uint32_t seq = oldest + static_cast<uint32_t>(step - 1);
  const char* text = editor_.history_find(seq);
  if (text == nullptr) return false;
  begin("history");
  add(" n=%lu line=%s", ul(seq), text);
  reply_end();
  return seq < newest;
}

void Console::cmd_echo(size_t argc, char** argv) {
  if (argc == 2 && (std::strcmp(argv[1], "on") == 0 || std::strcmp(argv[1], "off") == 0)) {
    echo_ = argv[1][1] == 'n';
  } else if (argc != 1) {
    error("echo: usage: echo [on|off]");
    return;
  }
  begin("echo");
  add(" %s", echo_ ? "on" : "off");
  reply_end();
}

// The site's commissioned range calibration (docs/commissioning.md): a count
// line, then one line per anchor/tag pair. The site is constant after start-up,
// so no snapshot is needed.
void Console::cmd_cal(size_t argc, char**) {
  if (argc != 1) {
    error("cal: takes no arguments");
    return;
  }
  start_job(Job::kCal, false);
}

bool Console::step_cal(size_t step) {
  const SiteConfig& site = app_.board().site;
  const bool calibrated = !std::isnan(site.range_offset_sigma_m);
  const size_t pairs = calibrated ? site.num_anchors * site.num_tags : 0;
  if (step == 0) {
    begin("cal");
    add(" status=%s pairs=%lu", calibrated ? "calibrated" : "uncalibrated", static_cast<unsigned long>(pairs));
    if (calibrated) add_fixed(" sigma_m=", site.range_offset_sigma_m, 4);
    if (calibrated && !std::isnan(site.range_systematic_sigma_m)) {
      add_fixed(" systematic_sigma_m=", site.range_systematic_sigma_m, 4);
    }
    reply_end();
    return pairs > 0;
  }
  const size_t k = step - 1;
  const size_t a = k / site.num_tags;
  const size_t t = k % site.num_tags;
  begin("cal");
  add(" anchor=%u tag=%u", static_cast<unsigned>(site.anchors[a].id), static_cast<unsigned>(site.tags[t].id));
  add_fixed(" offset_m=", site.range_offset_m[a][t], 4);
  add_fixed(" sigma_m=", site.range_offset_sigma_m, 4);
  reply_end();
  return step < pairs;
}

}  // namespace uwbnav
