// Scenario text parser, loader and validation (format in docs/simulator.md).
#include "tools/sim/scenario.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "estimator/types.hpp"

namespace uwbnav::sim {
namespace {

std::string trim(const std::string& s) {
  size_t b = 0;
  size_t e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t' || s[b] == '\r')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r')) --e;
  return s.substr(b, e - b);
}

std::vector<std::string> split_ws(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream is(s);
  std::string w;
  while (is >> w) out.push_back(w);
  return out;
}

bool parse_double(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0' || !std::isfinite(v)) return false;
  out = v;
  return true;
}

// Parses exactly n numbers separated by white space.
bool parse_numbers(const std::string& value, size_t n, double* out, std::string* why) {
  const std::vector<std::string> words = split_ws(value);
  if (words.size() != n) {
    *why = "expected " + std::to_string(n) + " numbers, got " + std::to_string(words.size());
    return false;
  }
  for (size_t i = 0; i < n; ++i) {
    if (!parse_double(words[i], out[i])) {
      *why = "not a finite number: '" + words[i] + "'";
      return false;
    }
  }
  return true;
}

using Setter = std::function<bool(Scenario&, const std::string&, std::string*)>;

// Scalar setter for a double field with an inclusive range.
template <typename Get>
Setter real(Get get, double lo, double hi) {
  return [get, lo, hi](Scenario& s, const std::string& v, std::string* why) {
    double x = 0.0;
    if (!parse_numbers(v, 1, &x, why)) return false;
    if (x < lo || x > hi) {
      std::ostringstream os;
      os << "value " << x << " outside [" << lo << ", " << hi << "]";
      *why = os.str();
      return false;
    }
    get(s) = x;
    return true;
  };
}

template <typename Get>
Setter flag(Get get) {
  return [get](Scenario& s, const std::string& v, std::string* why) {
    if (v == "1" || v == "true" || v == "yes") {
      get(s) = true;
      return true;
    }
    if (v == "0" || v == "false" || v == "no") {
      get(s) = false;
      return true;
    }
    *why = "expected 0 or 1, got '" + v + "'";
    return false;
  };
}

// Setter for an enum field from a fixed list of names.
template <typename Get, typename E>
Setter choice(Get get, std::vector<std::pair<std::string, E>> names) {
  return [get, names](Scenario& s, const std::string& v, std::string* why) {
    std::string list;
    for (const auto& n : names) {
      if (n.first == v) {
        get(s) = n.second;
        return true;
      }
      list += (list.empty() ? "" : ", ") + n.first;
    }
    *why = "expected one of " + list + ", got '" + v + "'";
    return false;
  };
}

bool parse_id(const std::string& w, unsigned long max, unsigned long& out, std::string* why) {
  double x = 0.0;
  if (!parse_double(w, x) || x < 0.0 || x > static_cast<double>(max) || std::floor(x) != x) {
    *why = "id must be an integer in [0, " + std::to_string(max) + "], got '" + w + "'";
    return false;
  }
  out = static_cast<unsigned long>(x);
  return true;
}

// One maneuver from words w[first..] ("KIND ARGS...").
bool parse_maneuver(const std::vector<std::string>& w, size_t first, Maneuver& mv, std::string* why) {
  size_t nargs = 0;
  if (w.size() <= first) {
    *why = "empty maneuver";
    return false;
  }
  const std::string& kind = w[first];
  if (kind == "hold") {
    mv.kind = ManeuverKind::kHold;
    nargs = 1;
  } else if (kind == "speed") {
    mv.kind = ManeuverKind::kSpeed;
    nargs = 2;
  } else if (kind == "turn") {
    mv.kind = ManeuverKind::kTurn;
    nargs = 2;
  } else if (kind == "climb") {
    mv.kind = ManeuverKind::kClimb;
    nargs = 2;
  } else if (kind == "goto") {
    mv.kind = ManeuverKind::kGoto;
    nargs = 4;
  } else if (kind == "eight") {
    mv.kind = ManeuverKind::kEight;
    nargs = 5;
  } else {
    *why = "unknown maneuver '" + kind + "' (hold, speed, turn, climb, goto, eight)";
    return false;
  }
  if (w.size() != first + nargs + 1) {
    *why = "maneuver '" + kind + "' needs " + std::to_string(nargs) + " number(s)";
    return false;
  }
  double x[5] = {0, 0, 0, 0, 0};
  for (size_t i = 0; i < nargs; ++i) {
    if (!parse_double(w[first + i + 1], x[i])) {
      *why = "not a finite number: '" + w[first + i + 1] + "'";
      return false;
    }
  }
  mv.duration_s = x[nargs - 1];
  mv.value = nargs == 2 ? x[0] : 0.0;
  if (nargs > 2) {
    for (size_t i = 0; i + 1 < nargs; ++i) mv.arg[i] = x[i];
  }
  if (mv.kind == ManeuverKind::kEight && (!(mv.arg[3] >= 1.0) || std::floor(mv.arg[3]) != mv.arg[3])) {
    *why = "eight needs a whole number of loops >= 1";
    return false;
  }
  if (!(mv.duration_s >= 0.1) || mv.duration_s > 1e6) {
    *why = "maneuver duration must be in [0.1, 1e6] s";
    return false;
  }
  if (mv.kind == ManeuverKind::kSpeed && (mv.value < 0.0 || mv.value > 100.0)) {
    *why = "speed must be in [0, 100] m/s";
    return false;
  }
  return true;
}

bool parse_vehicle_id(const std::string& w, uint16_t& out, std::string* why) {
  unsigned long id = 0;
  if (!parse_id(w, kNoVehicleId - 1U, id, why) || !is_vehicle_id(static_cast<uint16_t>(id))) {
    *why = "vehicle id must be an integer in [" + std::to_string(kFirstVehicleId) + ", " +
           std::to_string(kNoVehicleId - 1U) + "], got '" + w + "'";
    return false;
  }
  out = static_cast<uint16_t>(id);
  return true;
}

NeighbourDef* find_vehicle(Scenario& s, uint16_t id) {
  for (NeighbourDef& n : s.coop.vehicles) {
    if (n.id == id) return &n;
  }
  return nullptr;
}

// The vehicle a per-vehicle key names (it must have been defined by `vehicle` before).
NeighbourDef* vehicle_for(Scenario& s, const std::string& w, std::string* why) {
  uint16_t id = 0;
  if (!parse_vehicle_id(w, id, why)) return nullptr;
  NeighbourDef* n = find_vehicle(s, id);
  if (n == nullptr) *why = "vehicle " + w + " not defined yet (coop.vehicle = ID ... first)";
  return n;
}

const std::map<std::string, Setter>& setters() {
  static const std::map<std::string, Setter> table = [] {
    std::map<std::string, Setter> m;
    constexpr double kBig = 1e9;
    // [scenario]
    m["scenario.name"] = [](Scenario& s, const std::string& v, std::string* why) {
      if (v.empty()) {
        *why = "empty name";
        return false;
      }
      s.name = v;
      return true;
    };
    m["scenario.description"] = [](Scenario& s, const std::string& v, std::string*) {
      s.description = v;
      return true;
    };
    m["scenario.duration_s"] = real([](Scenario& s) -> double& { return s.duration_s; }, 0.01, 24.0 * 3600.0);
    m["scenario.platform"] = [](Scenario& s, const std::string& v, std::string* why) {
      if (v != "ground" && v != "air") {
        *why = "platform must be ground or air, got '" + v + "'";
        return false;
      }
      s.platform = v;
      return true;
    };
    m["scenario.gravity_mps2"] = real([](Scenario& s) -> double& { return s.gravity_mps2; }, 9.7, 9.9);
    // [site]
    m["site.anchor"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      if (w.size() != 4) {
        *why = "anchor needs 'ID X Y Z'";
        return false;
      }
      AnchorDef a;
      unsigned long id = 0;
      if (!parse_id(w[0], 65535, id, why)) return false;
      a.id = static_cast<uint16_t>(id);
      for (int i = 0; i < 3; ++i) {
        if (!parse_double(w[static_cast<size_t>(i) + 1], a.pos_nav_m[i])) {
          *why = "anchor coordinate not a finite number";
          return false;
        }
      }
      s.anchors.push_back(a);
      return true;
    };
    m["site.tag"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      if (w.size() != 4) {
        *why = "tag needs 'ID X Y Z' (lever arm, body frame FLU)";
        return false;
      }
      TagDef t;
      unsigned long id = 0;
      if (!parse_id(w[0], 255, id, why)) return false;
      t.id = static_cast<uint8_t>(id);
      for (int i = 0; i < 3; ++i) {
        if (!parse_double(w[static_cast<size_t>(i) + 1], t.lever_body_m[i])) {
          *why = "tag lever arm not a finite number";
          return false;
        }
      }
      s.tags.push_back(t);
      return true;
    };
    m["site.survey_sigma_m"] = real([](Scenario& s) -> double& { return s.site.survey_sigma_m; }, 0, 10);
    // [imu]
    m["imu.grade"] = [](Scenario& s, const std::string& v, std::string* why) {
      if (apply_imu_grade(v, s.imu)) return true;
      std::string list;
      for (const std::string& g : imu_grade_names()) list += (list.empty() ? "" : ", ") + g;
      *why = "unknown IMU grade '" + v + "' (" + list + ")";
      return false;
    };
    m["imu.vibration_accel_mps2"] =
        real([](Scenario& s) -> double& { return s.imu.vibration_accel_mps2; }, 0, 100);
    m["imu.vibration_gyro_dps"] = real([](Scenario& s) -> double& { return s.imu.vibration_gyro_dps; }, 0, 100);
    m["imu.vibration_hz"] = real([](Scenario& s) -> double& { return s.imu.vibration_hz; }, 0, 5000);
    m["imu.vibration_bandwidth_hz"] =
        real([](Scenario& s) -> double& { return s.imu.vibration_bandwidth_hz; }, 0.1, 1000);
    m["imu.enabled"] = flag([](Scenario& s) -> bool& { return s.imu.enabled; });
    m["imu.rate_hz"] = real([](Scenario& s) -> double& { return s.imu.rate_hz; }, 1.0, 10000.0);
    m["imu.gyro_bias_sigma_dps"] = real([](Scenario& s) -> double& { return s.imu.gyro_bias_sigma_dps; }, 0, 100);
    m["imu.gyro_arw_dps_per_sqrt_h"] =
        real([](Scenario& s) -> double& { return s.imu.gyro_arw_dps_per_sqrt_h; }, 0, 100);
    m["imu.gyro_bias_rw_dps_per_sqrt_s"] =
        real([](Scenario& s) -> double& { return s.imu.gyro_bias_rw_dps_per_sqrt_s; }, 0, 10);
    m["imu.accel_bias_sigma_mg"] = real([](Scenario& s) -> double& { return s.imu.accel_bias_sigma_mg; }, 0, 1000);
    m["imu.accel_noise_ug_per_sqrt_hz"] =
        real([](Scenario& s) -> double& { return s.imu.accel_noise_ug_per_sqrt_hz; }, 0, 1e5);
    m["imu.accel_bias_rw_mps2_per_sqrt_s"] =
        real([](Scenario& s) -> double& { return s.imu.accel_bias_rw_mps2_per_sqrt_s; }, 0, 10);
    m["imu.gyro_range_dps"] = real([](Scenario& s) -> double& { return s.imu.gyro_range_dps; }, 1, 1e4);
    m["imu.accel_range_g"] = real([](Scenario& s) -> double& { return s.imu.accel_range_g; }, 1, 1000);
    m["imu.gyro_lsb_dps"] = real([](Scenario& s) -> double& { return s.imu.gyro_lsb_dps; }, 0, 10);
    m["imu.accel_lsb_mg"] = real([](Scenario& s) -> double& { return s.imu.accel_lsb_mg; }, 0, 100);
    // [uwb]
    m["uwb.rate_hz"] = real([](Scenario& s) -> double& { return s.uwb.rate_hz; }, 0.1, 1000.0);
    m["uwb.offset_ms"] = real([](Scenario& s) -> double& { return s.uwb.offset_ms; }, 0, 1000.0);
    m["uwb.sigma_m"] = real([](Scenario& s) -> double& { return s.uwb.sigma_m; }, 0, 10);
    m["uwb.packet_loss"] = real([](Scenario& s) -> double& { return s.uwb.packet_loss; }, 0, 1);
    m["uwb.channel_diagnostics"] = flag([](Scenario& s) -> bool& { return s.uwb.channel_diagnostics; });
    m["uwb.outage"] = [](Scenario& s, const std::string& v, std::string* why) {
      double x[2] = {0, 0};
      if (!parse_numbers(v, 2, x, why)) return false;
      if (!(x[1] > x[0]) || x[0] < 0.0) {
        *why = "outage needs 0 <= START_S < END_S";
        return false;
      }
      s.uwb.outages.push_back(Outage{x[0], x[1]});
      return true;
    };
    m["uwb.schedule"] = choice([](Scenario& s) -> UwbSchedule& { return s.uwb.schedule; },
                               std::vector<std::pair<std::string, UwbSchedule>>{
                                   {"round_robin", UwbSchedule::kRoundRobin},
                                   {"per_anchor", UwbSchedule::kPerAnchor},
                                   {"frame", UwbSchedule::kFrame}});
    m["uwb.range_lsb_m"] = real([](Scenario& s) -> double& { return s.uwb.range_lsb_m; }, 0, 1);
    m["uwb.anchor_offset_sigma_m"] = real([](Scenario& s) -> double& { return s.uwb.anchor_offset_sigma_m; }, 0, 10);
    m["uwb.tag_offset_sigma_m"] = real([](Scenario& s) -> double& { return s.uwb.tag_offset_sigma_m; }, 0, 10);
    m["uwb.pair_offset_sigma_m"] = real([](Scenario& s) -> double& { return s.uwb.pair_offset_sigma_m; }, 0, 10);
    m["uwb.anchor_offset"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      RangeOffset o;
      unsigned long id = 0;
      if (w.size() != 2) {
        *why = "anchor_offset needs 'ANCHOR_ID METRES'";
        return false;
      }
      if (!parse_id(w[0], 65535, id, why)) return false;
      if (!parse_double(w[1], o.offset_m) || std::fabs(o.offset_m) > 100.0) {
        *why = "offset must be a number in [-100, 100] m";
        return false;
      }
      o.anchor_id = static_cast<uint16_t>(id);
      s.uwb.anchor_offsets.push_back(o);
      return true;
    };
    m["uwb.tag_offset"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      RangeOffset o;
      unsigned long id = 0;
      if (w.size() != 2) {
        *why = "tag_offset needs 'TAG_ID METRES'";
        return false;
      }
      if (!parse_id(w[0], 255, id, why)) return false;
      if (!parse_double(w[1], o.offset_m) || std::fabs(o.offset_m) > 100.0) {
        *why = "offset must be a number in [-100, 100] m";
        return false;
      }
      o.tag_id = static_cast<uint8_t>(id);
      s.uwb.tag_offsets.push_back(o);
      return true;
    };
    m["uwb.pair_offset"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      RangeOffset o;
      unsigned long aid = 0;
      unsigned long tid = 0;
      if (w.size() != 3) {
        *why = "pair_offset needs 'ANCHOR_ID TAG_ID METRES'";
        return false;
      }
      if (!parse_id(w[0], 65535, aid, why) || !parse_id(w[1], 255, tid, why)) return false;
      if (!parse_double(w[2], o.offset_m) || std::fabs(o.offset_m) > 100.0) {
        *why = "offset must be a number in [-100, 100] m";
        return false;
      }
      o.anchor_id = static_cast<uint16_t>(aid);
      o.tag_id = static_cast<uint8_t>(tid);
      s.uwb.pair_offsets.push_back(o);
      return true;
    };
    m["uwb.scale_common_pct"] = real([](Scenario& s) -> double& { return s.uwb.scale_common_pct; }, -10, 10);
    m["uwb.scale_pair_sigma_pct"] = real([](Scenario& s) -> double& { return s.uwb.scale_pair_sigma_pct; }, 0, 10);
    m["uwb.burst_loss"] = real([](Scenario& s) -> double& { return s.uwb.burst_loss; }, 0, 0.95);
    m["uwb.burst_mean_len"] = real([](Scenario& s) -> double& { return s.uwb.burst_mean_len; }, 1, 1e6);
    m["uwb.block_anchors"] = [](Scenario& s, const std::string& v, std::string* why) {
      unsigned long k = 0;
      if (!parse_id(v, kMaxAnchors, k, why)) return false;
      s.uwb.block_anchors = static_cast<size_t>(k);
      return true;
    };
    m["uwb.block_min_s"] = real([](Scenario& s) -> double& { return s.uwb.block_min_s; }, 0.01, 1e6);
    m["uwb.block_max_s"] = real([](Scenario& s) -> double& { return s.uwb.block_max_s; }, 0.01, 1e6);
    m["uwb.block_gap_min_s"] = real([](Scenario& s) -> double& { return s.uwb.block_gap_min_s; }, 0, 1e6);
    m["uwb.block_gap_max_s"] = real([](Scenario& s) -> double& { return s.uwb.block_gap_max_s; }, 0, 1e6);
    m["uwb.max_range_m"] = real([](Scenario& s) -> double& { return s.uwb.max_range_m; }, 0, 1e6);
    // [gnss]
    m["gnss.enabled"] = flag([](Scenario& s) -> bool& { return s.gnss.enabled; });
    m["gnss.rate_hz"] = real([](Scenario& s) -> double& { return s.gnss.rate_hz; }, 0.1, 100);
    m["gnss.latency_ms"] = real([](Scenario& s) -> double& { return s.gnss.latency_ms; }, 0, 10000);
    m["gnss.latency_jitter_ms"] = real([](Scenario& s) -> double& { return s.gnss.latency_jitter_ms; }, 0, 10000);
    m["gnss.lever_m"] = [](Scenario& s, const std::string& v, std::string* why) {
      double x[3] = {0, 0, 0};
      if (!parse_numbers(v, 3, x, why)) return false;
      for (int i = 0; i < 3; ++i) {
        if (std::fabs(x[i]) > 100.0) {
          *why = "lever arm must be within [-100, 100] m per axis";
          return false;
        }
        s.gnss.lever_body_m[i] = x[i];
      }
      return true;
    };
    m["gnss.sigma_h_m"] = real([](Scenario& s) -> double& { return s.gnss.sigma_h_m; }, 0, 100);
    m["gnss.sigma_v_m"] = real([](Scenario& s) -> double& { return s.gnss.sigma_v_m; }, 0, 100);
    m["gnss.tau_s"] = real([](Scenario& s) -> double& { return s.gnss.tau_s; }, 0.1, 1e5);
    m["gnss.sigma_white_m"] = real([](Scenario& s) -> double& { return s.gnss.sigma_white_m; }, 0, 100);
    m["gnss.claim_ratio"] = real([](Scenario& s) -> double& { return s.gnss.claim_ratio; }, 0.01, 100);
    m["gnss.vel_sigma_mps"] = real([](Scenario& s) -> double& { return s.gnss.vel_sigma_mps; }, 0.001, 100);
    m["gnss.num_sv"] = [](Scenario& s, const std::string& v, std::string* why) {
      unsigned long n = 0;
      if (!parse_id(v, 255, n, why)) return false;
      s.gnss.num_sv = static_cast<unsigned>(n);
      return true;
    };
    m["gnss.multipath_bias_m"] = real([](Scenario& s) -> double& { return s.gnss.multipath_bias_m; }, 0, 1000);
    m["gnss.multipath_turn_dps"] = real([](Scenario& s) -> double& { return s.gnss.multipath_turn_dps; }, 0, 360);
    m["gnss.multipath_claim_factor"] =
        real([](Scenario& s) -> double& { return s.gnss.multipath_claim_factor; }, 0.1, 100);
    for (const auto& kind : {std::pair<const char*, GnssWindowKind>{"blocked", GnssWindowKind::kBlocked},
                             std::pair<const char*, GnssWindowKind>{"multipath", GnssWindowKind::kMultipath}}) {
      const GnssWindowKind k = kind.second;
      m[std::string("gnss.") + kind.first] = [k](Scenario& s, const std::string& v, std::string* why) {
        double x[2] = {0, 0};
        if (!parse_numbers(v, 2, x, why)) return false;
        if (!(x[1] > x[0]) || x[0] < 0.0) {
          *why = "window needs 0 <= START_S < END_S";
          return false;
        }
        s.gnss.windows.push_back(GnssWindow{k, x[0], x[1]});
        return true;
      };
    }
    // [nlos]
    m["nlos.episode_share"] = real([](Scenario& s) -> double& { return s.nlos.episode_share; }, 0, 0.95);
    m["nlos.episode_mean_s"] = real([](Scenario& s) -> double& { return s.nlos.episode_mean_s; }, 0.01, 1e5);
    m["nlos.episode_length_law"] =
        choice([](Scenario& s) -> RandomLaw& { return s.nlos.episode_length_law; },
               std::vector<std::pair<std::string, RandomLaw>>{{"exponential", RandomLaw::kExponential},
                                                              {"lognormal", RandomLaw::kLogNormal}});
    m["nlos.episode_length_shape"] =
        real([](Scenario& s) -> double& { return s.nlos.episode_length_shape; }, 0, 3);
    m["nlos.episode_bias_mean_m"] = real([](Scenario& s) -> double& { return s.nlos.episode_bias_mean_m; }, 0, 100);
    m["nlos.episode_bias_law"] =
        choice([](Scenario& s) -> RandomLaw& { return s.nlos.episode_bias_law; },
               std::vector<std::pair<std::string, RandomLaw>>{{"exponential", RandomLaw::kExponential},
                                                              {"lognormal", RandomLaw::kLogNormal}});
    m["nlos.episode_extra_sigma_m"] =
        real([](Scenario& s) -> double& { return s.nlos.episode_extra_sigma_m; }, 0, 100);
    m["nlos.box"] = [](Scenario& s, const std::string& v, std::string* why) {
      double x[6] = {0, 0, 0, 0, 0, 0};
      if (!parse_numbers(v, 6, x, why)) return false;
      Box b;
      for (int i = 0; i < 3; ++i) {
        b.min_nav_m[i] = x[i];
        b.max_nav_m[i] = x[i + 3];
        if (!(b.max_nav_m[i] > b.min_nav_m[i])) {
          *why = "box needs XMIN YMIN ZMIN XMAX YMAX ZMAX with max > min";
          return false;
        }
      }
      s.nlos.boxes.push_back(b);
      return true;
    };
    m["nlos.box_bias_mean_m"] = real([](Scenario& s) -> double& { return s.nlos.box_bias_mean_m; }, 0, 100);
    m["nlos.box_extra_sigma_m"] = real([](Scenario& s) -> double& { return s.nlos.box_extra_sigma_m; }, 0, 100);
    m["nlos.body_block"] = flag([](Scenario& s) -> bool& { return s.nlos.body_block; });
    m["nlos.body_cone_deg"] = real([](Scenario& s) -> double& { return s.nlos.body_cone_deg; }, 0, 180);
    m["nlos.body_bias_mean_m"] = real([](Scenario& s) -> double& { return s.nlos.body_bias_mean_m; }, 0, 100);
    m["nlos.body_extra_sigma_m"] = real([](Scenario& s) -> double& { return s.nlos.body_extra_sigma_m; }, 0, 100);
    m["nlos.bias_shape"] = real([](Scenario& s) -> double& { return s.nlos.bias_shape; }, 0, 3);
    m["nlos.bias_jitter_shape"] = real([](Scenario& s) -> double& { return s.nlos.bias_jitter_shape; }, 0, 3);
    m["nlos.outlier_prob"] = real([](Scenario& s) -> double& { return s.nlos.outlier_prob; }, 0, 1);
    m["nlos.outlier_min_m"] = real([](Scenario& s) -> double& { return s.nlos.outlier_min_m; }, 0.01, kBig);
    m["nlos.outlier_max_m"] = real([](Scenario& s) -> double& { return s.nlos.outlier_max_m; }, 0.01, kBig);
    m["nlos.outlier_positive_prob"] =
        real([](Scenario& s) -> double& { return s.nlos.outlier_positive_prob; }, 0, 1);
    m["nlos.protocol"] = flag([](Scenario& s) -> bool& { return s.nlos.protocol; });
    m["nlos.protocol_fraction"] = real([](Scenario& s) -> double& { return s.nlos.protocol_fraction; }, 0, 1);
    m["nlos.protocol_mean_min_m"] = real([](Scenario& s) -> double& { return s.nlos.protocol_mean_min_m; }, 0, 100);
    m["nlos.protocol_mean_max_m"] = real([](Scenario& s) -> double& { return s.nlos.protocol_mean_max_m; }, 0, 100);
    m["nlos.protocol_spread_m"] = real([](Scenario& s) -> double& { return s.nlos.protocol_spread_m; }, 0, 100);
    // [channel]
    m["channel.rx_power_1m_dbm"] =
        real([](Scenario& s) -> double& { return s.channel.rx_power_1m_dbm; }, -150, 30);
    m["channel.path_loss_exponent"] =
        real([](Scenario& s) -> double& { return s.channel.path_loss_exponent; }, 0.5, 6);
    m["channel.shadowing_sigma_db"] =
        real([](Scenario& s) -> double& { return s.channel.shadowing_sigma_db; }, 0, 30);
    m["channel.nlos_extra_loss_db"] =
        real([](Scenario& s) -> double& { return s.channel.nlos_extra_loss_db; }, 0, 60);
    m["channel.los_gap_mean_db"] = real([](Scenario& s) -> double& { return s.channel.los_gap_mean_db; }, 0, 60);
    m["channel.los_gap_sigma_db"] = real([](Scenario& s) -> double& { return s.channel.los_gap_sigma_db; }, 0, 30);
    m["channel.nlos_gap_mean_db"] = real([](Scenario& s) -> double& { return s.channel.nlos_gap_mean_db; }, 0, 60);
    m["channel.nlos_gap_sigma_db"] =
        real([](Scenario& s) -> double& { return s.channel.nlos_gap_sigma_db; }, 0, 30);
    // [vehicle]
    m["vehicle.roll_gain_deg_per_mps2"] =
        real([](Scenario& s) -> double& { return s.vehicle.roll_gain_deg_per_mps2; }, -10, 10);
    m["vehicle.pitch_gain_deg_per_mps2"] =
        real([](Scenario& s) -> double& { return s.vehicle.pitch_gain_deg_per_mps2; }, -10, 10);
    // [route]
    m["route.start"] = [](Scenario& s, const std::string& v, std::string* why) {
      double x[4] = {0, 0, 0, 0};
      if (!parse_numbers(v, 4, x, why)) return false;
      for (int i = 0; i < 3; ++i) s.route.start_nav_m[i] = x[i];
      s.route.start_heading_deg = x[3];
      return true;
    };
    m["route.kind"] = choice([](Scenario& s) -> RouteKind& { return s.route.kind; },
                             std::vector<std::pair<std::string, RouteKind>>{
                                 {"vehicle", RouteKind::kVehicle}, {"multicopter", RouteKind::kMulticopter}});
    m["route.yaw"] = [](Scenario& s, const std::string& v, std::string* why) {
      double x[2] = {0, 0};
      if (!parse_numbers(v, 2, x, why)) return false;
      if (!(x[1] >= 0.1) || x[1] > 1e6) {
        *why = "yaw needs 'DEG DURATION_S' with a duration in [0.1, 1e6] s";
        return false;
      }
      Maneuver mv;
      mv.kind = ManeuverKind::kTurn;
      mv.value = x[0];
      mv.duration_s = x[1];
      s.route.yaw_turns.push_back(mv);
      return true;
    };
    m["route.loop_from"] = [](Scenario& s, const std::string& v, std::string* why) {
      unsigned long idx = 0;
      if (!parse_id(v, 1000000, idx, why)) return false;
      s.route.loop_from = static_cast<size_t>(idx);
      return true;
    };
    m["route.maneuver"] = [](Scenario& s, const std::string& v, std::string* why) {
      Maneuver mv;
      if (!parse_maneuver(split_ws(v), 0, mv, why)) return false;
      s.route.maneuvers.push_back(mv);
      return true;
    };
    // [coop]
    m["coop.vehicle"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      NeighbourDef n;
      if (w.size() < 2 || !parse_vehicle_id(w[0], n.id, why)) {
        if (w.size() < 2) *why = "vehicle needs 'ID offset DX DY' or 'ID route X Y Z HEADING'";
        return false;
      }
      if (find_vehicle(s, n.id) != nullptr) {
        *why = "duplicate vehicle id " + w[0];
        return false;
      }
      double x[4] = {0, 0, 0, 0};
      if (w[1] == "offset") {
        if (w.size() != 4 || !parse_double(w[2], x[0]) || !parse_double(w[3], x[1])) {
          *why = "vehicle needs 'ID offset DX DY' (metres ahead of and left of the ego's start)";
          return false;
        }
        n.motion = NeighbourMotion::kOffset;
        n.offset_m[0] = x[0];
        n.offset_m[1] = x[1];
      } else if (w[1] == "route") {
        for (size_t i = 0; i < 4; ++i) {
          if (w.size() != 6 || !parse_double(w[i + 2], x[i])) {
            *why = "vehicle needs 'ID route X Y Z HEADING' (start pose; maneuvers from vehicle_maneuver)";
            return false;
          }
        }
        n.motion = NeighbourMotion::kRoute;
        for (int i = 0; i < 3; ++i) n.route.start_nav_m[i] = x[i];
        n.route.start_heading_deg = x[3];
      } else {
        *why = "unknown vehicle motion '" + w[1] + "' (offset, route)";
        return false;
      }
      s.coop.vehicles.push_back(n);
      return true;
    };
    m["coop.vehicle_maneuver"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      NeighbourDef* n = w.empty() ? nullptr : vehicle_for(s, w[0], why);
      if (n == nullptr) {
        if (w.empty()) *why = "vehicle_maneuver needs 'ID KIND ...'";
        return false;
      }
      if (n->motion != NeighbourMotion::kRoute) {
        *why = "vehicle " + w[0] + " follows the ego's route (offset): it takes no maneuvers";
        return false;
      }
      Maneuver mv;
      if (!parse_maneuver(w, 1, mv, why)) return false;
      if (mv.kind == ManeuverKind::kGoto || mv.kind == ManeuverKind::kEight) {
        *why = "a vehicle takes hold, speed, turn and climb maneuvers only";
        return false;
      }
      n->route.maneuvers.push_back(mv);
      return true;
    };
    m["coop.vehicle_tag"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      NeighbourDef* n = w.size() == 4 ? vehicle_for(s, w[0], why) : nullptr;
      if (n == nullptr) {
        if (w.size() != 4) *why = "vehicle_tag needs 'ID X Y Z' (lever arm, its body frame FLU)";
        return false;
      }
      double x[3] = {0, 0, 0};
      for (size_t i = 0; i < 3; ++i) {
        if (!parse_double(w[i + 1], x[i]) || std::fabs(x[i]) > 100.0) {
          *why = "vehicle tag lever arm must be numbers within [-100, 100] m";
          return false;
        }
      }
      for (int i = 0; i < 3; ++i) n->tag_lever_body_m[i] = x[i];
      return true;
    };
    m["coop.vehicle_error"] = [](Scenario& s, const std::string& v, std::string* why) {
      const std::vector<std::string> w = split_ws(v);
      NeighbourDef* n = w.size() == 5 ? vehicle_for(s, w[0], why) : nullptr;
      if (n == nullptr) {
        if (w.size() != 5) *why = "vehicle_error needs 'ID ALONG_M CROSS_M UP_M TAU_S'";
        return false;
      }
      double x[4] = {0, 0, 0, 0};
      for (size_t i = 0; i < 4; ++i) {
        if (!parse_double(w[i + 1], x[i]) || !(x[i] > 0.0) || x[i] > 1e5) {
          *why = "vehicle_error sigmas and correlation time must be > 0";
          return false;
        }
      }
      for (int i = 0; i < 3; ++i) n->sigma_m[i] = x[i];
      n->tau_s = x[3];
      return true;
    };
    m["coop.rate_hz"] = real([](Scenario& s) -> double& { return s.coop.rate_hz; }, 0.1, 100);
    m["coop.latency_ms"] = real([](Scenario& s) -> double& { return s.coop.latency_ms; }, 0, 10000);
    m["coop.latency_jitter_ms"] = real([](Scenario& s) -> double& { return s.coop.latency_jitter_ms; }, 0, 10000);
    m["coop.vel_sigma_mps"] = real([](Scenario& s) -> double& { return s.coop.vel_sigma_mps; }, 0, 100);
    m["coop.dependent"] = flag([](Scenario& s) -> bool& { return s.coop.dependent; });
    m["coop.range_rate_hz"] = real([](Scenario& s) -> double& { return s.coop.range_rate_hz; }, 0.1, 1000);
    m["coop.range_offset_ms"] = real([](Scenario& s) -> double& { return s.coop.range_offset_ms; }, 0, 1000);
    m["coop.box_m"] = [](Scenario& s, const std::string& v, std::string* why) {
      double x[3] = {0, 0, 0};
      if (!parse_numbers(v, 3, x, why)) return false;
      for (int i = 0; i < 3; ++i) {
        if (!(x[i] > 0.0) || x[i] > 100.0) {
          *why = "box_m needs LENGTH WIDTH HEIGHT in (0, 100] m";
          return false;
        }
        s.coop.box_m[i] = x[i];
      }
      return true;
    };
    m["coop.nlos_bias_min_m"] = real([](Scenario& s) -> double& { return s.coop.nlos_bias_min_m; }, 0, 100);
    m["coop.nlos_bias_max_m"] = real([](Scenario& s) -> double& { return s.coop.nlos_bias_max_m; }, 0, 100);
    m["coop.nlos_extra_sigma_m"] = real([](Scenario& s) -> double& { return s.coop.nlos_extra_sigma_m; }, 0, 100);
    return m;
  }();
  return table;
}

Status fail(std::string* error, const std::string& msg) {
  if (error != nullptr) *error = msg;
  return Status::kInvalidArgument;
}

Status parse_into(const std::string& text, const std::string& origin, Scenario& out, std::string* error,
                  int depth) {
  std::istringstream is(text);
  std::string line;
  std::string section;
  int line_no = 0;
  bool seen_key = false;
  while (std::getline(is, line)) {
    ++line_no;
    const std::string where = origin + ":" + std::to_string(line_no) + ": ";
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    line = trim(line);
    if (line.empty()) continue;
    if (line.front() == '[') {
      if (line.back() != ']' || line.size() < 3) return fail(error, where + "bad section header '" + line + "'");
      section = trim(line.substr(1, line.size() - 2));
      static const std::set<std::string> kSections = {"scenario", "site",    "imu",     "uwb",
                                                      "nlos",     "channel", "vehicle", "route", "gnss",
                                                      "coop"};
      if (kSections.count(section) == 0) return fail(error, where + "unknown section [" + section + "]");
      continue;
    }
    const size_t eq = line.find('=');
    if (eq == std::string::npos) return fail(error, where + "expected 'key = value'");
    const std::string key = trim(line.substr(0, eq));
    const std::string value = trim(line.substr(eq + 1));
    if (key.empty()) return fail(error, where + "missing key before '='");
    if (section.empty()) {
      if (key != "base") return fail(error, where + "key '" + key + "' outside a section (only 'base' allowed)");
      if (seen_key) return fail(error, where + "'base' must come before any other key");
      if (depth > 0) return fail(error, where + "a preset cannot have a base");
      const std::string base = preset_text(value);
      if (base.empty()) return fail(error, where + "unknown base preset '" + value + "'");
      const Status st = parse_into(base, value, out, error, depth + 1);
      if (!ok(st)) return st;
      seen_key = true;
      continue;
    }
    seen_key = true;
    const auto it = setters().find(section + "." + key);
    if (it == setters().end()) return fail(error, where + "unknown key '" + key + "' in [" + section + "]");
    std::string why;
    if (!it->second(out, value, &why)) return fail(error, where + key + ": " + why);
  }
  return Status::kOk;
}

// An integer number of microseconds per period of `rate_hz`.
bool integer_period(double rate_hz) {
  const double period_us = 1e6 / rate_hz;
  return std::fabs(period_us - std::round(period_us)) <= 1e-6;
}

Status validate_coop(const Scenario& s, const std::set<uint16_t>& anchor_ids, std::string* error) {
  const CoopConfig& c = s.coop;
  if (c.vehicles.empty()) return Status::kOk;
  if (c.vehicles.size() > kMaxSimVehicles) {
    return fail(error, "coop: more than " + std::to_string(kMaxSimVehicles) + " vehicles");
  }
  for (const NeighbourDef& n : c.vehicles) {
    const std::string id = std::to_string(n.id);
    if (anchor_ids.count(n.id) != 0) return fail(error, "coop: vehicle id " + id + " is an anchor id");
    if (n.motion == NeighbourMotion::kOffset && s.route.kind != RouteKind::kVehicle) {
      return fail(error, "coop: vehicle " + id + " follows the ego's route (offset), which needs route.kind = vehicle");
    }
    if (n.motion == NeighbourMotion::kRoute && n.route.maneuvers.empty()) {
      return fail(error, "coop: vehicle " + id + " has a route but no vehicle_maneuver");
    }
  }
  if (!integer_period(c.rate_hz)) return fail(error, "coop.rate_hz must divide 1e6 us into an integer period");
  if (!integer_period(c.range_rate_hz)) {
    return fail(error, "coop.range_rate_hz must divide 1e6 us into an integer period");
  }
  if (c.range_offset_ms * 1e3 >= 1e6 / c.range_rate_hz) {
    return fail(error, "coop.range_offset_ms must be shorter than the range period");
  }
  const double slots_per_s = c.range_rate_hz * static_cast<double>(c.vehicles.size() * s.tags.size());
  if (slots_per_s > 10000.0) return fail(error, "coop: more than 10000 inter-vehicle range slots per second");
  if (c.latency_jitter_ms > c.latency_ms) return fail(error, "coop.latency_jitter_ms exceeds coop.latency_ms");
  if (c.nlos_bias_max_m < c.nlos_bias_min_m) return fail(error, "coop.nlos_bias_max_m < coop.nlos_bias_min_m");
  return Status::kOk;
}

}  // namespace

void snap_to_recording_precision(Scenario& s) {
  // The recording carries gravity, anchors and lever arms as floats; simulate
  // with exactly those values so the estimator sees the simulated site.
  const auto to_float = [](double& x) { x = static_cast<double>(static_cast<float>(x)); };
  to_float(s.gravity_mps2);
  for (AnchorDef& a : s.anchors) {
    for (double& x : a.pos_nav_m) to_float(x);
  }
  for (TagDef& t : s.tags) {
    for (double& x : t.lever_body_m) to_float(x);
  }
  for (double& x : s.gnss.lever_body_m) to_float(x);
}

std::vector<std::string> imu_grade_names() { return {"consumer", "mems", "automotive"}; }

bool apply_imu_grade(const std::string& grade, ImuConfig& imu) {
  // consumer: phone / small-drone MEMS (accel 300-400 ug/sqrt(Hz), ARW 0.3-0.5
  // deg/sqrt(h), turn-on 1-2 deg/s, 30-50 mg); mems: the seed 000 Table 1
  // default; automotive: automotive/tactical-grade MEMS (50 ug/sqrt(Hz), 0.05
  // deg/sqrt(h), 0.05 deg/s, 2 mg). Figures in the middle of those ranges.
  if (grade == "consumer") {
    imu.accel_noise_ug_per_sqrt_hz = 350.0;
    imu.gyro_arw_dps_per_sqrt_h = 0.4;
    imu.gyro_bias_sigma_dps = 1.5;
    imu.accel_bias_sigma_mg = 40.0;
    imu.gyro_bias_rw_dps_per_sqrt_s = 0.002;
    imu.accel_bias_rw_mps2_per_sqrt_s = 2e-4;
    imu.gyro_range_dps = 2000.0;
    imu.accel_range_g = 16.0;
    return true;
  }
  if (grade == "mems") {
    const ImuConfig d;
    imu.accel_noise_ug_per_sqrt_hz = d.accel_noise_ug_per_sqrt_hz;
    imu.gyro_arw_dps_per_sqrt_h = d.gyro_arw_dps_per_sqrt_h;
    imu.gyro_bias_sigma_dps = d.gyro_bias_sigma_dps;
    imu.accel_bias_sigma_mg = d.accel_bias_sigma_mg;
    imu.gyro_bias_rw_dps_per_sqrt_s = d.gyro_bias_rw_dps_per_sqrt_s;
    imu.accel_bias_rw_mps2_per_sqrt_s = d.accel_bias_rw_mps2_per_sqrt_s;
    imu.gyro_range_dps = d.gyro_range_dps;
    imu.accel_range_g = d.accel_range_g;
    return true;
  }
  if (grade == "automotive") {
    imu.accel_noise_ug_per_sqrt_hz = 50.0;
    imu.gyro_arw_dps_per_sqrt_h = 0.05;
    imu.gyro_bias_sigma_dps = 0.05;
    imu.accel_bias_sigma_mg = 2.0;
    imu.gyro_bias_rw_dps_per_sqrt_s = 0.0001;
    imu.accel_bias_rw_mps2_per_sqrt_s = 1e-5;
    imu.gyro_range_dps = 300.0;
    imu.accel_range_g = 10.0;
    return true;
  }
  return false;
}

std::vector<std::string> scenario_keys() {
  std::vector<std::string> keys;
  keys.reserve(setters().size());
  for (const auto& kv : setters()) keys.push_back(kv.first);
  return keys;
}

Status parse_scenario(const std::string& text, const std::string& origin, Scenario& out, std::string* error) {
  Scenario s;
  const Status st = parse_into(text, origin, s, error, 0);
  if (!ok(st)) return st;
  snap_to_recording_precision(s);
  const Status v = validate_scenario(s, error);
  if (!ok(v)) {
    if (error != nullptr) *error = origin + ": " + *error;
    return v;
  }
  out = std::move(s);
  return Status::kOk;
}

Status load_scenario(const std::string& name_or_path, Scenario& out, std::string* error) {
  const std::string preset = preset_text(name_or_path);
  if (!preset.empty()) return parse_scenario(preset, name_or_path, out, error);
  std::ifstream f(name_or_path, std::ios::binary);
  if (!f) {
    if (error != nullptr) *error = "'" + name_or_path + "' is neither a preset nor a readable scenario file";
    return Status::kNotFound;
  }
  std::ostringstream ss;
  ss << f.rdbuf();
  return parse_scenario(ss.str(), name_or_path, out, error);
}

Status validate_scenario(const Scenario& s, std::string* error) {
  if (s.anchors.empty()) return fail(error, "no anchor (site.anchor = ID X Y Z)");
  if (s.anchors.size() > kMaxAnchors) return fail(error, "too many anchors (max " + std::to_string(kMaxAnchors) + ")");
  if (s.tags.empty()) return fail(error, "no tag (site.tag = ID X Y Z)");
  if (s.tags.size() > kMaxTags) return fail(error, "too many tags (max " + std::to_string(kMaxTags) + ")");
  std::set<uint16_t> anchor_ids;
  for (const AnchorDef& a : s.anchors) {
    if (!anchor_ids.insert(a.id).second) return fail(error, "duplicate anchor id " + std::to_string(a.id));
  }
  std::set<uint8_t> tag_ids;
  for (const TagDef& t : s.tags) {
    if (!tag_ids.insert(t.id).second) return fail(error, "duplicate tag id " + std::to_string(t.id));
  }
  const double imu_period_us = 1e6 / s.imu.rate_hz;
  if (std::fabs(imu_period_us - std::round(imu_period_us)) > 1e-6) {
    return fail(error, "imu.rate_hz must divide 1e6 us into an integer period");
  }
  if (s.uwb.schedule == UwbSchedule::kRoundRobin) {
    const double uwb_period_us = 1e6 / s.uwb.rate_hz;
    if (std::fabs(uwb_period_us - std::round(uwb_period_us)) > 1e-6) {
      return fail(error, "uwb.rate_hz must divide 1e6 us into an integer period");
    }
  }
  const double slots_per_s = s.uwb.schedule == UwbSchedule::kPerAnchor
                                 ? s.uwb.rate_hz * static_cast<double>(s.anchors.size())
                                 : s.uwb.rate_hz;
  if (slots_per_s > 10000.0) return fail(error, "uwb: more than 10000 range slots per second per tag");
  if (s.uwb.offset_ms * 1e3 >= 1e6 / slots_per_s) {
    return fail(error, "uwb.offset_ms must be shorter than the range period");
  }
  for (const RangeOffset& o : s.uwb.anchor_offsets) {
    if (anchor_ids.count(o.anchor_id) == 0) return fail(error, "uwb.anchor_offset: unknown anchor " + std::to_string(o.anchor_id));
  }
  for (const RangeOffset& o : s.uwb.tag_offsets) {
    if (tag_ids.count(o.tag_id) == 0) return fail(error, "uwb.tag_offset: unknown tag " + std::to_string(o.tag_id));
  }
  for (const RangeOffset& o : s.uwb.pair_offsets) {
    if (anchor_ids.count(o.anchor_id) == 0 || tag_ids.count(o.tag_id) == 0) {
      return fail(error, "uwb.pair_offset: unknown anchor " + std::to_string(o.anchor_id) + " or tag " +
                             std::to_string(o.tag_id));
    }
  }
  if (s.uwb.block_anchors > s.anchors.size()) return fail(error, "uwb.block_anchors exceeds the number of anchors");
  if (s.uwb.block_max_s < s.uwb.block_min_s) return fail(error, "uwb.block_max_s < uwb.block_min_s");
  if (s.uwb.block_gap_max_s < s.uwb.block_gap_min_s) return fail(error, "uwb.block_gap_max_s < uwb.block_gap_min_s");
  if (s.uwb.block_anchors > 0 && s.uwb.block_gap_max_s <= 0.0 && s.uwb.block_min_s <= 0.0) {
    return fail(error, "uwb: blockage schedule needs a positive gap or blockage length");
  }
  if (s.imu.vibration_hz > 0.0 && s.imu.vibration_hz >= 0.5 * s.imu.rate_hz) {
    return fail(error, "imu.vibration_hz must be below the Nyquist frequency (rate_hz / 2)");
  }
  if (s.gnss.enabled) {
    const GnssConfig& g = s.gnss;
    const double gnss_period_us = 1e6 / g.rate_hz;
    if (std::fabs(gnss_period_us - std::round(gnss_period_us)) > 1e-6) {
      return fail(error, "gnss.rate_hz must divide 1e6 us into an integer period");
    }
    if (g.latency_jitter_ms > g.latency_ms) return fail(error, "gnss.latency_jitter_ms exceeds gnss.latency_ms");
    if (!(std::hypot(g.sigma_h_m, g.sigma_white_m) > 0.0) || !(std::hypot(g.sigma_v_m, g.sigma_white_m) > 0.0)) {
      return fail(error, "gnss: sigma_h_m, sigma_v_m and sigma_white_m give a zero claimed sigma");
    }
  }
  const Status coop = validate_coop(s, anchor_ids, error);
  if (!ok(coop)) return coop;
  const bool copter = s.route.kind == RouteKind::kMulticopter;
  for (const Maneuver& mv : s.route.maneuvers) {
    const bool air_only = mv.kind == ManeuverKind::kGoto || mv.kind == ManeuverKind::kEight;
    const bool ground_only =
        mv.kind == ManeuverKind::kSpeed || mv.kind == ManeuverKind::kTurn || mv.kind == ManeuverKind::kClimb;
    if (copter && ground_only) return fail(error, "route.kind = multicopter takes hold, goto and eight maneuvers only");
    if (!copter && air_only) return fail(error, "goto and eight maneuvers need route.kind = multicopter");
  }
  if (!copter && !s.route.yaw_turns.empty()) return fail(error, "route.yaw needs route.kind = multicopter");
  if (s.nlos.outlier_max_m < s.nlos.outlier_min_m) return fail(error, "nlos.outlier_max_m < nlos.outlier_min_m");
  if (s.nlos.protocol_mean_max_m < s.nlos.protocol_mean_min_m) {
    return fail(error, "nlos.protocol_mean_max_m < nlos.protocol_mean_min_m");
  }
  if (!s.route.maneuvers.empty() && s.route.loop_from >= s.route.maneuvers.size()) {
    return fail(error, "route.loop_from must index a maneuver (0.." + std::to_string(s.route.maneuvers.size() - 1) +
                           ")");
  }
  return Status::kOk;
}

}  // namespace uwbnav::sim
