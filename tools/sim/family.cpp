// Scenario family (see family.hpp): per cell the ranges every drive is drawn
// from, a route planner for random ground drives (lots, roads, trolleys) and
// multicopter flights, random anchor layouts, obstacles, error models, GNSS and
// neighbour vehicles (the cooperative street canyon).
#include "tools/sim/family.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "tools/sim/rng.hpp"
#include "tools/sim/trajectory.hpp"

namespace uwbnav::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Closed interval a quantity is drawn from (lo == hi: fixed).
struct Span {
  double lo = 0.0;
  double hi = 0.0;
};

double draw(Rng& r, Span s) { return s.hi > s.lo ? r.uniform(s.lo, s.hi) : s.lo; }
// Log-uniform (scale quantities: rates, lengths).
double draw_log(Rng& r, Span s) {
  return s.hi > s.lo && s.lo > 0.0 ? std::exp(r.uniform(std::log(s.lo), std::log(s.hi))) : s.lo;
}
int draw_int(Rng& r, int lo, int hi) { return hi > lo ? lo + static_cast<int>(r.below(static_cast<uint64_t>(hi - lo + 1))) : lo; }

// kGnss: a long road with anchors at one end only, GNSS throughout (ground_gnss).
// kCoop: a street canyon with anchors at one end, neighbour vehicles, GNSS at the open ends (coop_canyon).
enum class CellKind : uint8_t { kGround, kAir, kTrolley, kOutage, kGnss, kCoop };

// IMU grades as bits, in the order of imu_grade_names().
constexpr unsigned kConsumer = 1U;
constexpr unsigned kMems = 2U;
constexpr unsigned kAutomotive = 4U;

// What one cell draws, within these ranges (docs/simulator.md "Scenario family").
struct CellSpec {
  const char* name = "";
  const char* description = "";
  CellKind kind = CellKind::kGround;
  Span duration_s{60, 180};
  int anchors_min = 4, anchors_max = 4;
  Span anchor_height_m{1.0, 2.5};  // base height of the layout
  Span anchor_spread_m{0.0, 0.5};  // each anchor +/- U[0, spread] around the base
  Span rate_hz{5, 50};             // per anchor (log-uniform)
  double total_rate_hz = 0.0;      // > 0: round-robin at about this total rate instead (sparse cells)
  Span sigma_m{0.05, 0.15};
  Span episode_share{0, 0};
  Span episode_mean_s{0.1, 10};    // log-uniform
  Span episode_bias_m{0.3, 1.0};
  double body_block_prob = 0.0;
  int boxes_min = 0, boxes_max = 0;
  Span outlier_prob{0, 0};
  Span scale_pct{0, 0.05};         // |common part|; per-pair sigma U[0, hi / 3]
  Span offset_sigma_m{0, 0.03};    // per-anchor offsets N(0, sigma)
  Span survey_sigma_m{0, 0.03};
  Span packet_loss{0, 0.03};
  Span burst_loss{0, 0};
  Span burst_len{2, 10};
  unsigned grades = kMems | kAutomotive;  // IMU grades drawn from (bit set)
  Span speed_mps{2, 8};            // cruise speed
  double road_prob = 0.2;          // share of drives on a long straight road
  size_t block_anchors = 0;
  Span vibration_mps2{0, 0};       // multicopter rotor vibration (accelerometer RMS)
};

std::vector<CellSpec> make_specs() {
  std::vector<CellSpec> v;
  {
    CellSpec c;
    c.name = "ground_los";
    c.description = "ground vehicle, 4 anchors, line of sight only; small offsets, scale and survey errors";
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "ground_nlos";
    c.description = "ground vehicle, 4 anchors, seed-000-like lot: parked vans, body NLOS, random NLOS episodes 10-40 %, outliers";
    c.episode_share = {0.10, 0.40};
    c.episode_mean_s = {0.3, 5};
    c.body_block_prob = 1.0;
    c.boxes_min = 2;
    c.boxes_max = 4;
    c.outlier_prob = {0.002, 0.01};
    c.scale_pct = {0, 0.1};
    c.offset_sigma_m = {0, 0.05};
    c.survey_sigma_m = {0, 0.05};
    c.packet_loss = {0.01, 0.05};
    c.burst_loss = {0, 0.05};
    c.grades = kConsumer | kMems | kAutomotive;
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "ground_hard";
    c.description = "ground vehicle, 4-8 anchors, NLOS up to 60 %, offsets to 0.15 m, scale to 0.3 %, survey to 0.2 m, burst loss";
    c.anchors_max = 8;
    c.rate_hz = {2, 50};
    c.episode_share = {0.2, 0.6};
    c.episode_bias_m = {0.3, 1.5};
    c.body_block_prob = 0.7;
    c.boxes_min = 0;
    c.boxes_max = 4;
    c.outlier_prob = {0.005, 0.02};
    c.scale_pct = {0, 0.3};
    c.offset_sigma_m = {0, 0.15};
    c.survey_sigma_m = {0, 0.2};
    c.packet_loss = {0.01, 0.1};
    c.burst_loss = {0.02, 0.15};
    c.burst_len = {3, 20};
    c.speed_mps = {1, 15};
    c.grades = kConsumer | kMems | kAutomotive;
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "ground_survey15";
    c.description = "ground vehicle, 4-8 anchors whose surveyed positions are off by N(0, 0.15 m) per axis; otherwise mild";
    c.anchors_max = 8;
    c.survey_sigma_m = {0.15, 0.15};
    c.episode_share = {0, 0.1};
    c.body_block_prob = 0.5;
    c.outlier_prob = {0, 0.005};
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "ground_blocked";
    c.description = "long ground drive (10-20 min), 4 anchors, 2 of them silent for 5-20 s at a time, body NLOS";
    c.duration_s = {600, 1200};
    c.rate_hz = {5, 20};
    c.block_anchors = 2;
    c.body_block_prob = 1.0;
    c.episode_share = {0, 0.1};
    c.outlier_prob = {0, 0.005};
    c.speed_mps = {2, 12};
    c.road_prob = 0.3;
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "ground_sparse";
    c.description = "ground vehicle, 4-8 anchors ranging at only 1-5 Hz each; mild NLOS";
    c.anchors_max = 8;
    c.rate_hz = {1, 5};
    c.episode_share = {0, 0.2};
    c.body_block_prob = 0.5;
    c.outlier_prob = {0, 0.005};
    c.burst_loss = {0, 0.05};
    c.grades = kConsumer | kMems | kAutomotive;
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "air_indoor";
    c.description = "indoor multicopter, 6 anchors at 0.4-2.9 m, ~25 Hz each, random initial yaw (no heading source), rotor vibration";
    c.kind = CellKind::kAir;
    c.anchors_min = c.anchors_max = 6;
    c.rate_hz = {15, 40};
    c.episode_share = {0, 0.3};
    c.outlier_prob = {0, 0.005};
    c.scale_pct = {0, 0.3};
    c.offset_sigma_m = {0, 0.1};
    c.survey_sigma_m = {0, 0.05};
    c.burst_loss = {0, 0.05};
    c.grades = kConsumer | kMems;
    c.speed_mps = {0.3, 2};
    c.vibration_mps2 = {0.05, 0.5};
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "air_sparse";
    c.description = "indoor multicopter, ~1 range/s in total over 6 anchors, consumer IMU with vibration";
    c.kind = CellKind::kAir;
    c.duration_s = {80, 180};
    c.anchors_min = c.anchors_max = 6;
    c.total_rate_hz = 1.0;
    c.episode_share = {0, 0.2};
    c.outlier_prob = {0, 0.01};
    c.scale_pct = {0, 0.3};
    c.offset_sigma_m = {0, 0.1};
    c.survey_sigma_m = {0, 0.05};
    c.packet_loss = {0, 0.05};
    c.grades = kConsumer;
    c.speed_mps = {0.3, 2};
    c.vibration_mps2 = {0.1, 0.6};
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "trolley3";
    c.description = "3-tag trolley (tags 0.3 m apart), 8 anchors at 1.04 m, frames of all 24 ranges at 100 Hz, 1 cm quantisation, per-pair offsets 0.1-0.3 m, no IMU";
    c.kind = CellKind::kTrolley;
    c.duration_s = {60, 120};
    c.anchors_min = c.anchors_max = 8;
    c.anchor_height_m = {1.04, 1.04};
    c.anchor_spread_m = {0, 0};
    c.rate_hz = {100, 100};
    c.sigma_m = {0.05, 0.05};
    c.episode_share = {0, 0.1};
    c.outlier_prob = {0, 0.002};
    c.scale_pct = {0, 0.1};
    c.offset_sigma_m = {0, 0};
    c.survey_sigma_m = {0, 0.02};
    c.packet_loss = {0, 0.02};
    c.speed_mps = {0.3, 1.2};
    c.road_prob = 0.0;
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "outage";
    c.description = "full UWB outages of 5, 10, 15 or 30 s at random speeds and turn rates: parking drives, long straights and multicopter flights";
    c.kind = CellKind::kOutage;
    c.duration_s = {150, 200};
    c.anchors_max = 6;
    c.rate_hz = {10, 50};
    c.body_block_prob = 0.3;
    c.episode_share = {0, 0.05};
    c.speed_mps = {1, 15};
    c.road_prob = 0.35;
    c.grades = kConsumer | kMems | kAutomotive;
    c.vibration_mps2 = {0.05, 0.3};
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "ground_gnss";
    c.description = "350-600 m road, 4 anchors along its first 50-80 m only (UWB range 60-100 m): out of coverage >= 20 s and back; GNSS throughout with blocked and multipath windows, latency, lever arm";
    c.kind = CellKind::kGnss;
    c.duration_s = {120, 300};
    c.rate_hz = {10, 30};
    c.episode_share = {0, 0.1};
    c.body_block_prob = 0.5;
    c.outlier_prob = {0, 0.005};
    c.speed_mps = {10, 15};
    c.road_prob = 1.0;
    v.push_back(c);
  }
  {
    CellSpec c;
    c.name = "coop_canyon";
    c.description = "250-350 m street canyon, 4-6 anchors over its first 40-55 m only (UWB range 45-65 m), out and back at 3-10 m/s; 2-3 neighbour vehicles (convoy, adjacent lane, oncoming) broadcasting honest states at 10 Hz, ranges to their tags (NLOS through a third vehicle); GNSS at the open ends, blocked or multipath inside";
    c.kind = CellKind::kCoop;
    c.duration_s = {60, 300};  // drawn, then replaced by the planned drive's length
    c.anchors_max = 6;
    c.rate_hz = {10, 30};
    c.episode_share = {0, 0.1};
    c.body_block_prob = 0.3;
    c.outlier_prob = {0, 0.005};
    c.speed_mps = {3, 10};
    c.road_prob = 1.0;
    v.push_back(c);
  }
  return v;
}

const std::vector<CellSpec>& specs() {
  static const std::vector<CellSpec> s = make_specs();
  return s;
}

// FNV-1a of the cell name: different cells with the same seed draw different drives.
uint64_t name_hash(const std::string& s) {
  uint64_t h = 0xCBF29CE484222325ULL;
  for (char ch : s) {
    h ^= static_cast<uint8_t>(ch);
    h *= 0x100000001B3ULL;
  }
  return h;
}

double wrap_pi(double a) {
  while (a > kPi) a -= 2.0 * kPi;
  while (a < -kPi) a += 2.0 * kPi;
  return a;
}

// Rectangle the route keeps to [m].
struct Area {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double w() const { return x1 - x0; }
  double h() const { return y1 - y0; }
};

// Forward kinematics of ground maneuvers (planning only; the truth comes from
// Trajectory): the same smooth step S(u) = u - sin(2 pi u) / (2 pi), midpoint rule.
struct GroundPlanner {
  double t = 0, x = 0, y = 0, yaw = 0, v = 0;
  std::vector<Maneuver> out;

  void push(ManeuverKind kind, double value, double dur) {
    dur = std::max(0.1, std::round(dur * 100.0) / 100.0);
    Maneuver m;
    m.kind = kind;
    m.value = value;
    m.duration_s = dur;
    out.push_back(m);
    const double dv = kind == ManeuverKind::kSpeed ? value - v : 0.0;
    const double dyaw = kind == ManeuverKind::kTurn ? value * kDeg : 0.0;
    const int n = std::max(1, static_cast<int>(dur / 0.02));
    const double h = dur / n;
    for (int i = 0; i < n; ++i) {
      const double u = (i + 0.5) / n;
      const double s = u - std::sin(2.0 * kPi * u) / (2.0 * kPi);
      const double vv = v + dv * s;
      const double yy = yaw + dyaw * s;
      x += vv * std::cos(yy) * h;
      y += vv * std::sin(yy) * h;
    }
    v += dv;
    yaw += dyaw;
    t += dur;
  }
};

// Random drive inside `area`: parked start, then towards random targets with
// braking before turns, straights at cruise speed, stops and S-bends; on a road
// (`road`) back and forth between the two ends (long straights, U-turns).
void plan_ground(Rng& r, const Area& area, double v_cruise, double duration_s, bool road, bool trolley,
                 RouteConfig& route) {
  const double a_lat = trolley ? 0.5 : 3.0;  // peak lateral acceleration [m/s^2]
  const double a_lon = trolley ? 0.3 : 1.5;  // mean longitudinal acceleration [m/s^2]
  const double inset = trolley ? 1.5 : std::min(8.0, 0.25 * std::min(area.w(), area.h()));
  GroundPlanner p;
  p.x = road ? area.x0 + inset : r.uniform(area.x0 + inset, area.x1 - inset);
  p.y = r.uniform(area.y0 + inset, area.y1 - inset);
  p.yaw = road ? 0.0 : r.uniform(-kPi, kPi);
  route.start_nav_m[0] = p.x;
  route.start_nav_m[1] = p.y;
  route.start_nav_m[2] = 0.0;
  route.start_heading_deg = p.yaw / kDeg;
  const double v_turn =
      trolley ? v_cruise * r.uniform(0.5, 1.0) : std::min(v_cruise, road ? r.uniform(1.5, 3.0) : r.uniform(2.0, 3.5));
  const double min_leg = std::min(15.0, 0.4 * std::hypot(area.w(), area.h()));
  p.push(ManeuverKind::kHold, 0.0, r.uniform(10.0, 14.0));
  bool far_end = true;
  while (p.t < duration_s + 2.0) {
    double tx = 0.0;
    double ty = 0.0;
    if (road) {
      tx = far_end ? area.x1 - inset : area.x0 + inset;
      ty = r.uniform(area.y0 + 0.4 * area.h(), area.y1 - 0.4 * area.h());
      far_end = !far_end;
    } else {
      for (int tries = 0; tries < 20; ++tries) {
        tx = r.uniform(area.x0 + inset, area.x1 - inset);
        ty = r.uniform(area.y0 + inset, area.y1 - inset);
        if (std::hypot(tx - p.x, ty - p.y) >= min_leg) break;
      }
    }
    if (p.v < 0.5 * v_turn) p.push(ManeuverKind::kSpeed, v_turn, std::max(2.0, 1.5 * (v_turn - p.v) / a_lon));
    const double dyaw = wrap_pi(std::atan2(ty - p.y, tx - p.x) - p.yaw);
    if (std::fabs(dyaw) > 5.0 * kDeg) {
      if (p.v > v_turn + 0.1) p.push(ManeuverKind::kSpeed, v_turn, std::max(2.0, 1.5 * (p.v - v_turn) / a_lon));
      p.push(ManeuverKind::kTurn, dyaw / kDeg, std::max(1.5, 2.0 * std::fabs(dyaw) * p.v / a_lat));
    }
    const double dist = std::hypot(tx - p.x, ty - p.y);
    // Straight: accelerate to the highest speed (<= cruise) that still leaves room to brake.
    double vc = std::max(v_cruise, p.v);
    double need = 0.0;
    for (int it = 0; it < 12; ++it) {
      const double ta = std::max(2.0, 1.5 * (vc - p.v) / a_lon);
      const double tb = std::max(2.0, 1.5 * (vc - v_turn) / a_lon);
      need = 0.5 * (p.v + vc) * ta + 0.5 * (vc + v_turn) * tb;
      if (need <= dist || vc <= p.v + 0.2) break;
      vc = 0.5 * (vc + p.v);
    }
    if (vc > p.v + 0.2) p.push(ManeuverKind::kSpeed, vc, std::max(2.0, 1.5 * (vc - p.v) / a_lon));
    if (dist > need && p.v > 0.1) p.push(ManeuverKind::kHold, 0.0, (dist - need) / p.v);
    // End of the straight: stop for a while, or brake to turning speed (then maybe an S-bend).
    const double u = r.uniform();
    if (u < 0.25) {
      p.push(ManeuverKind::kSpeed, 0.0, std::max(2.0, 1.5 * p.v / a_lon));
      p.push(ManeuverKind::kHold, 0.0, r.uniform(2.0, 8.0));
      continue;
    }
    if (p.v > v_turn + 0.1) p.push(ManeuverKind::kSpeed, v_turn, std::max(2.0, 1.5 * (p.v - v_turn) / a_lon));
    if (u < 0.45 && !road && !trolley) {
      const double th = r.uniform(10.0, 25.0);
      const double td = std::max(1.5, 2.0 * th * kDeg * p.v / a_lat);
      p.push(ManeuverKind::kTurn, th, td);
      p.push(ManeuverKind::kTurn, -th, td);
    }
  }
  // Past the end of the run: stop and stay (the route never loops).
  p.push(ManeuverKind::kSpeed, 0.0, std::max(2.0, 1.5 * p.v / a_lon));
  p.push(ManeuverKind::kHold, 0.0, 1e5);
  route.kind = RouteKind::kVehicle;
  route.maneuvers = p.out;
  route.loop_from = route.maneuvers.size() - 1;
}

// Path length of one figure-eight loop (x = A sin phi, y = B sin 2 phi) [m].
double eight_length(double A, double B) {
  constexpr int kN = 400;
  double len = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double ph = (i + 0.5) * 2.0 * kPi / kN;
    len += std::hypot(A * std::cos(ph), 2.0 * B * std::cos(2.0 * ph)) * 2.0 * kPi / kN;
  }
  return len;
}

// Multicopter flight in the room `area`: on the ground with a random heading,
// take-off to 1-2.5 m, random waypoints, figure-eights and hover phases at
// 0.3-2 m/s peak, yaw turns on their own timeline, landing.
void plan_air(Rng& r, const Area& area, Span speed, double duration_s, RouteConfig& route) {
  constexpr double kPeak = 2.1875;  // peak / mean speed of the 7th-order smooth step
  const double m = 1.0;             // keep 1 m from the walls
  double x = r.uniform(area.x0 + 1.5, area.x1 - 1.5);
  double y = r.uniform(area.y0 + 1.5, area.y1 - 1.5);
  double z = 0.1;
  route = RouteConfig{};
  route.kind = RouteKind::kMulticopter;
  route.start_nav_m[0] = x;
  route.start_nav_m[1] = y;
  route.start_nav_m[2] = z;
  route.start_heading_deg = r.uniform(-180.0, 180.0);
  double t = 0.0;
  const auto push = [&](ManeuverKind kind, double a0, double a1, double a2, double a3, double dur) {
    Maneuver mv;
    mv.kind = kind;
    mv.duration_s = std::max(0.5, std::round(dur * 100.0) / 100.0);
    mv.arg[0] = a0;
    mv.arg[1] = a1;
    mv.arg[2] = a2;
    mv.arg[3] = a3;
    route.maneuvers.push_back(mv);
    t += mv.duration_s;
  };
  const auto go = [&](double nx, double ny, double nz, double v_peak) {
    const double d = std::sqrt((nx - x) * (nx - x) + (ny - y) * (ny - y) + (nz - z) * (nz - z));
    push(ManeuverKind::kGoto, nx, ny, nz, 0.0, std::max(2.0, kPeak * d / v_peak));
    x = nx;
    y = ny;
    z = nz;
  };
  push(ManeuverKind::kHold, 0, 0, 0, 0, r.uniform(10.0, 14.0));
  go(x, y, r.uniform(1.0, 2.5), r.uniform(0.3, 0.8));
  const double landing_s = 15.0;
  while (t < duration_s - landing_s) {
    const double u = r.uniform();
    const double v_peak = r.uniform(speed.lo, speed.hi);
    if (u < 0.45) {
      go(r.uniform(area.x0 + m, area.x1 - m), r.uniform(area.y0 + m, area.y1 - m), r.uniform(0.8, 2.5), v_peak);
    } else if (u < 0.7) {
      push(ManeuverKind::kHold, 0, 0, 0, 0, r.uniform(1.0, 6.0));
    } else {
      const double A = r.uniform(1.0, std::max(1.0, std::min(3.0, 0.5 * area.w() - m - 0.5)));
      const double B = r.uniform(0.5, std::max(0.5, std::min(2.0, 0.5 * area.h() - m - 0.5)));
      const double reach = std::hypot(A, B);
      const double cx = r.uniform(area.x0 + m + reach, std::max(area.x0 + m + reach, area.x1 - m - reach));
      const double cy = r.uniform(area.y0 + m + reach, std::max(area.y0 + m + reach, area.y1 - m - reach));
      go(cx, cy, z, v_peak);
      const double loops = static_cast<double>(draw_int(r, 1, 2));
      push(ManeuverKind::kEight, A, B, r.uniform(0.0, 180.0), loops, kPeak * eight_length(A, B) * loops / v_peak);
    }
  }
  go(x, y, 0.1, r.uniform(0.3, 0.6));
  push(ManeuverKind::kHold, 0, 0, 0, 0, 1e5);
  route.loop_from = route.maneuvers.size() - 1;
  // Yaw: holds and turns of 30-180 deg either way, independent of the position.
  double ty = 0.0;
  while (ty < duration_s) {
    Maneuver hold;
    hold.kind = ManeuverKind::kTurn;
    hold.value = 0.0;
    hold.duration_s = std::round(r.uniform(5.0, 30.0) * 100.0) / 100.0;
    route.yaw_turns.push_back(hold);
    ty += hold.duration_s;
    if (r.uniform() < 0.6) {
      Maneuver turn;
      turn.kind = ManeuverKind::kTurn;
      turn.value = (r.uniform() < 0.5 ? -1.0 : 1.0) * r.uniform(30.0, 180.0);
      turn.duration_s = std::round(r.uniform(3.0, 10.0) * 100.0) / 100.0;
      route.yaw_turns.push_back(turn);
      ty += turn.duration_s;
    }
  }
}

// n anchors spread around the rectangle `area` grown by `margin`, at jittered
// equal steps along its perimeter (random phase); heights base +/- spread.
void place_anchors(Rng& r, int n, const Area& area, double margin, double base_h, double spread,
                   std::vector<AnchorDef>& out) {
  const double x0 = area.x0 - margin, y0 = area.y0 - margin;
  const double w = area.w() + 2.0 * margin, h = area.h() + 2.0 * margin;
  const double perimeter = 2.0 * (w + h);
  const double phase = r.uniform();
  out.clear();
  for (int i = 0; i < n; ++i) {
    double s = (i + r.uniform(-0.25, 0.25)) / n + phase;
    s = (s - std::floor(s)) * perimeter;
    AnchorDef a;
    a.id = static_cast<uint16_t>(i + 1);
    if (s < w) {
      a.pos_nav_m[0] = x0 + s;
      a.pos_nav_m[1] = y0;
    } else if (s < w + h) {
      a.pos_nav_m[0] = x0 + w;
      a.pos_nav_m[1] = y0 + (s - w);
    } else if (s < 2.0 * w + h) {
      a.pos_nav_m[0] = x0 + w - (s - w - h);
      a.pos_nav_m[1] = y0 + h;
    } else {
      a.pos_nav_m[0] = x0;
      a.pos_nav_m[1] = y0 + h - (s - 2.0 * w - h);
    }
    a.pos_nav_m[2] = std::max(0.2, base_h + r.uniform(-spread, spread));
    out.push_back(a);
  }
}

// Road: n anchors from one end to the other at jittered equal spacing,
// alternating between the two sides, `margin` outside the road.
void place_road_anchors(Rng& r, int n, const Area& area, double margin, double base_h, double spread,
                        std::vector<AnchorDef>& out) {
  out.clear();
  const double step = area.w() / (n - 1);
  const bool left_first = r.uniform() < 0.5;
  for (int i = 0; i < n; ++i) {
    AnchorDef a;
    a.id = static_cast<uint16_t>(i + 1);
    const double jitter = (i == 0 || i == n - 1) ? 0.0 : r.uniform(-0.2, 0.2) * step;
    a.pos_nav_m[0] = area.x0 + i * step + jitter;
    a.pos_nav_m[1] = ((i % 2 == 0) == left_first) ? area.y1 + margin : area.y0 - margin;
    a.pos_nav_m[2] = std::max(0.2, base_h + r.uniform(-spread, spread));
    out.push_back(a);
  }
}

// Parked vans (5 x 2 x 2.5 m) just inside the area along its sides.
void place_boxes(Rng& r, int n, const Area& area, std::vector<Box>& out) {
  for (int i = 0; i < n; ++i) {
    const int side = draw_int(r, 0, 3);
    const double off = r.uniform(0.5, 3.0);
    Box b;
    if (side == 0 || side == 2) {
      const double cx = r.uniform(area.x0 + 3.0, area.x1 - 3.0);
      const double cy = side == 0 ? area.y0 + off : area.y1 - off;
      b = Box{{cx - 2.5, cy - 1.0, 0.0}, {cx + 2.5, cy + 1.0, 2.5}};
    } else {
      const double cy = r.uniform(area.y0 + 3.0, area.y1 - 3.0);
      const double cx = side == 1 ? area.x1 - off : area.x0 + off;
      b = Box{{cx - 1.0, cy - 2.5, 0.0}, {cx + 1.0, cy + 2.5, 2.5}};
    }
    out.push_back(b);
  }
}

// Random IMU of one of the cell's grades, each figure scaled by U[0.8, 1.25].
void draw_imu(Rng& r, const CellSpec& c, ImuConfig& imu, bool air) {
  std::vector<std::string> allowed;
  const std::vector<std::string> names = imu_grade_names();
  for (size_t i = 0; i < names.size(); ++i) {
    if ((c.grades & (1U << i)) != 0U) allowed.push_back(names[i]);
  }
  if (!apply_imu_grade(allowed[static_cast<size_t>(r.below(allowed.size()))], imu)) return;
  const auto jig = [&r](double& x) { x *= r.uniform(0.8, 1.25); };
  jig(imu.accel_noise_ug_per_sqrt_hz);
  jig(imu.gyro_arw_dps_per_sqrt_h);
  jig(imu.gyro_bias_sigma_dps);
  jig(imu.accel_bias_sigma_mg);
  if (air && c.vibration_mps2.hi > 0.0) {
    imu.vibration_accel_mps2 = draw(r, c.vibration_mps2);
    imu.vibration_gyro_dps = imu.vibration_accel_mps2 * r.uniform(1.0, 3.0);
    // Band-limited rotor vibration (aliased blade-pass frequency) or white.
    if (r.uniform() < 0.6) {
      imu.vibration_hz = r.uniform(15.0, 45.0);
      imu.vibration_bandwidth_hz = r.uniform(2.0, 10.0);
    }
  }
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// GNSS windows of one kind: n windows of U[len.lo, len.hi] s (rounded to 0.1 s)
// at random places in [20 s, duration - 5 s), at least 1 s from every window
// placed so far; a window that finds no room in 50 tries is left out.
void place_gnss_windows(Rng& r, GnssWindowKind kind, int n, Span len, double duration_s,
                        std::vector<GnssWindow>& windows) {
  for (int i = 0; i < n; ++i) {
    const double l = std::round(draw(r, len) * 10.0) / 10.0;
    for (int tries = 0; tries < 50; ++tries) {
      const double t0 = std::round(r.uniform(20.0, std::max(20.0, duration_s - 5.0 - l)) * 10.0) / 10.0;
      bool clear = t0 + l <= duration_s - 5.0;
      for (const GnssWindow& w : windows) clear = clear && (t0 + l + 1.0 <= w.start_s || t0 >= w.end_s + 1.0);
      if (!clear) continue;
      windows.push_back(GnssWindow{kind, t0, t0 + l});
      break;
    }
  }
  std::sort(windows.begin(), windows.end(),
            [](const GnssWindow& a, const GnssWindow& b) { return a.start_s < b.start_s; });
}

// A DGNSS-like receiver with drawn errors, misreported sigmas, latency and
// lever arm (no windows).
void draw_receiver(Rng& r, GnssConfig& g) {
  g.enabled = true;
  g.rate_hz = 5.0;
  g.latency_ms = std::round(r.uniform(50.0, 150.0));
  g.latency_jitter_ms = std::round(r.uniform(5.0, 20.0));
  g.lever_body_m[0] = r.uniform(0.0, 1.5);
  g.lever_body_m[1] = r.uniform(-0.2, 0.2);
  g.lever_body_m[2] = r.uniform(1.0, 1.8);
  g.sigma_h_m = r.uniform(0.3, 1.5);
  g.sigma_v_m = g.sigma_h_m * r.uniform(1.3, 2.0);
  g.tau_s = r.uniform(20.0, 60.0);
  g.sigma_white_m = r.uniform(0.05, 0.15);
  g.claim_ratio = r.uniform(0.7, 1.5);
  g.vel_sigma_mps = r.uniform(0.03, 0.1);
  g.num_sv = static_cast<unsigned>(draw_int(r, 9, 16));
  g.multipath_bias_m = r.uniform(2.0, 8.0);
  g.multipath_turn_dps = r.uniform(2.0, 10.0);
  g.multipath_claim_factor = 2.0;
  g.windows.clear();
}

// ground_gnss: UWB coverage limit and a DGNSS-like receiver with drawn errors,
// misreported sigmas, latency, lever arm, 1-3 blocked and 1-3 multipath windows.
void draw_gnss(Rng& r, double duration_s, Scenario& s) {
  s.uwb.max_range_m = std::round(r.uniform(60.0, 100.0));
  GnssConfig& g = s.gnss;
  draw_receiver(r, g);
  const int n_blocked = draw_int(r, 1, 3);
  const int n_multipath = draw_int(r, 1, 3);
  // One of each first, so that both kinds find room in a short drive.
  place_gnss_windows(r, GnssWindowKind::kBlocked, 1, Span{5.0, 20.0}, duration_s, g.windows);
  place_gnss_windows(r, GnssWindowKind::kMultipath, 1, Span{5.0, 30.0}, duration_s, g.windows);
  place_gnss_windows(r, GnssWindowKind::kBlocked, n_blocked - 1, Span{5.0, 20.0}, duration_s, g.windows);
  place_gnss_windows(r, GnssWindowKind::kMultipath, n_multipath - 1, Span{5.0, 30.0}, duration_s, g.windows);
}

// coop_canyon: the street and what the planner decided (for GNSS windows and neighbours).
struct Canyon {
  Area street;                     // carriageway: x along the street from the anchors' end, y across [m]
  double lane_w_m = 3.5;
  double out_lane_y_m = 0.0;       // the ego's lane on the way out (+x); it comes back two lanes left
  double oncoming_lane_y_m = 0.0;  // a lane nobody else uses, driven in -x
  double canyon_x0_m = 0.0;        // GNSS blocked or multipath for x in [x0, x1]
  double canyon_x1_m = 0.0;
  double v_cruise_mps = 0.0;       // the ego's cruise speed
};

// Lateral displacement of a 180 deg turn with the smooth step at speed v over T
// is v T times this: integral over u in [0, 1] of sin(pi S(u)), S(u) = u - sin(2 pi u) / (2 pi).
double uturn_lateral_factor() {
  constexpr int kSteps = 2000;
  double sum = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const double u = (i + 0.5) / kSteps;
    sum += std::sin(kPi * (u - std::sin(2.0 * kPi * u) / (2.0 * kPi)));
  }
  return sum / kSteps;
}

// Street canyon of 5 lanes, anchors over its first 40-55 m, the ego parked at
// the anchors' end, then out at cruise speed, a U-turn (two lanes left) near
// the far end, back and parked again among the anchors; the drive's length is
// what the route takes plus 5-10 s.
Canyon plan_canyon(Rng& r, const CellSpec& c, int n_anchors, const FamilyOptions& opt, Scenario& s) {
  Canyon k;
  const double length = r.uniform(250.0, 350.0);
  k.street = Area{0.0, 0.0, length, 5.0 * k.lane_w_m};
  k.out_lane_y_m = 1.5 * k.lane_w_m;
  k.oncoming_lane_y_m = 4.5 * k.lane_w_m;
  const Area zone{0.0, 0.0, r.uniform(40.0, 55.0), k.street.h()};
  const double base_h = draw(r, c.anchor_height_m);
  const double spread = draw(r, c.anchor_spread_m);
  place_road_anchors(r, n_anchors, zone, r.uniform(0.5, 2.5), base_h, spread, s.anchors);
  // A tag below the roof line (behind the windscreen), so other cars can shadow it.
  s.tags.push_back(TagDef{0, {r.uniform(0.0, 1.0), r.uniform(-0.2, 0.2), r.uniform(1.1, 1.4)}});

  constexpr double kALon = 1.5;  // mean longitudinal acceleration [m/s^2]
  const double v = draw(r, c.speed_mps);
  k.v_cruise_mps = v;
  const double v_turn = std::min(v, r.uniform(2.0, 2.5));
  GroundPlanner p;
  p.x = r.uniform(3.0, 8.0);
  p.y = k.out_lane_y_m;
  s.route.start_nav_m[0] = p.x;
  s.route.start_nav_m[1] = p.y;
  s.route.start_nav_m[2] = 0.0;
  s.route.start_heading_deg = 0.0;
  p.push(ManeuverKind::kHold, 0.0, r.uniform(10.0, 14.0));
  p.push(ManeuverKind::kSpeed, v, std::max(2.0, 1.5 * v / kALon));
  const double t_brake = std::max(2.0, 1.5 * (v - v_turn) / kALon);
  const double d_brake = v > v_turn + 0.1 ? 0.5 * (v + v_turn) * t_brake : 0.0;
  const double x_turn = length - 10.0;
  if (x_turn - d_brake - p.x > 1.0) p.push(ManeuverKind::kHold, 0.0, (x_turn - d_brake - p.x) / v);
  if (v > v_turn + 0.1) p.push(ManeuverKind::kSpeed, v_turn, t_brake);
  p.push(ManeuverKind::kTurn, 180.0, 2.0 * k.lane_w_m / (v_turn * uturn_lateral_factor()));
  if (v > v_turn + 0.1) p.push(ManeuverKind::kSpeed, v, std::max(2.0, 1.5 * (v - v_turn) / kALon));
  const double x_stop = r.uniform(15.0, 35.0);
  const double t_stop = std::max(2.0, 1.5 * v / kALon);
  const double d_stop = 0.5 * v * t_stop;
  if (p.x - x_stop - d_stop > 1.0) p.push(ManeuverKind::kHold, 0.0, (p.x - x_stop - d_stop) / v);
  p.push(ManeuverKind::kSpeed, 0.0, t_stop);
  p.push(ManeuverKind::kHold, 0.0, 1.0);
  s.route.maneuvers = p.out;
  s.route.loop_from = s.route.maneuvers.size() - 1;  // parked to the end
  double duration = std::round(p.t + r.uniform(5.0, 10.0));
  if (opt.fast) duration = std::min(duration, 150.0);
  s.duration_s = duration;
  k.canyon_x0_m = r.uniform(60.0, 90.0);
  k.canyon_x1_m = length - r.uniform(20.0, 40.0);
  return k;
}

// coop_canyon: UWB coverage, the ego's receiver with windows wherever the ego
// is inside the canyon (blocked or multipath, 5-20 s each), and 2-3 neighbour
// vehicles: a convoy car 8-18 m ahead, a second one 7-12 m ahead of it (so it
// is mostly ranged through the first) or 8-30 m behind, each up to 0.5 m off
// the ego's line, and maybe a car in the lane to the right (-15..15 m ahead)
// or an oncoming car in a lane of its own. The offset cars drive the ego's
// route translated (a rigid formation); the oncoming one starts beyond the far
// end after 0-40 s and drives through at 3-10 m/s.
void draw_coop(Rng& r, const Canyon& k, Scenario& s) {
  s.uwb.max_range_m = std::round(r.uniform(45.0, 65.0));
  GnssConfig& g = s.gnss;
  draw_receiver(r, g);
  Trajectory ego;
  ego.build(s, s.duration_s);
  bool inside = false;
  double t_in = 0.0;
  for (double t = 0.0;; t += 0.1) {
    const bool end = t >= s.duration_s - 1e-9;
    const double x = end ? 0.0 : ego.at(static_cast<uint64_t>(std::llround(t * 1e6))).pos_nav_m.x();
    const bool now_inside = !end && x >= k.canyon_x0_m && x <= k.canyon_x1_m;
    if (now_inside && !inside) t_in = std::round(t * 10.0) / 10.0;
    if (!now_inside && inside) {
      const double t_out = std::round(t * 10.0) / 10.0;
      for (double w0 = t_in; w0 < t_out;) {
        double w1 = std::min(t_out, w0 + std::round(r.uniform(5.0, 20.0) * 10.0) / 10.0);
        if (t_out - w1 < 0.5) w1 = t_out;  // no sliver of open sky inside the canyon
        const GnssWindowKind kind = r.uniform() < 0.5 ? GnssWindowKind::kBlocked : GnssWindowKind::kMultipath;
        g.windows.push_back(GnssWindow{kind, w0, w1});
        w0 = w1;
      }
    }
    inside = now_inside;
    if (end) break;
  }

  CoopConfig& co = s.coop;
  co.vehicles.clear();
  const auto add = [&](NeighbourDef n) {
    n.id = static_cast<uint16_t>(kFirstVehicleId + 1 + co.vehicles.size());
    n.tag_lever_body_m[0] = r.uniform(-0.5, 1.0);
    n.tag_lever_body_m[1] = r.uniform(-0.2, 0.2);
    n.tag_lever_body_m[2] = r.uniform(1.1, 1.4);
    n.sigma_m[0] = r.uniform(0.05, 0.2);
    n.sigma_m[1] = r.uniform(0.05, 0.2);
    n.sigma_m[2] = std::max(n.sigma_m[0], n.sigma_m[1]) * r.uniform(1.5, 2.5);
    n.tau_s = r.uniform(5.0, 20.0);
    co.vehicles.push_back(n);
  };
  const auto offset = [](double ahead_m, double left_m) {
    NeighbourDef n;
    n.motion = NeighbourMotion::kOffset;
    n.offset_m[0] = ahead_m;
    n.offset_m[1] = left_m;
    return n;
  };
  const double gap_m = r.uniform(8.0, 18.0);
  add(offset(gap_m, r.uniform(-0.5, 0.5)));
  if (r.uniform() < 0.5) {
    add(offset(gap_m + r.uniform(7.0, 12.0), r.uniform(-0.5, 0.5)));
  } else {
    add(offset(-r.uniform(8.0, 30.0), r.uniform(-0.5, 0.5)));
  }
  if (r.uniform() < 0.6) {
    if (r.uniform() < 0.5) {
      add(offset(r.uniform(-15.0, 15.0), -k.lane_w_m));
    } else {
      NeighbourDef n;
      n.motion = NeighbourMotion::kRoute;
      n.route.start_nav_m[0] = k.street.x1 + r.uniform(0.0, 30.0);
      n.route.start_nav_m[1] = k.oncoming_lane_y_m;
      n.route.start_heading_deg = 180.0;
      const double v = r.uniform(3.0, 10.0);
      Maneuver wait;
      wait.kind = ManeuverKind::kHold;
      wait.duration_s = std::round(r.uniform(0.1, 40.0) * 100.0) / 100.0;
      Maneuver go;
      go.kind = ManeuverKind::kSpeed;
      go.value = v;
      go.duration_s = std::max(2.0, std::round(v / 1.5 * 100.0) / 100.0);
      Maneuver cruise;
      cruise.kind = ManeuverKind::kHold;
      cruise.duration_s = 1.0;
      n.route.maneuvers = {wait, go, cruise};
      add(n);
    }
  }
  co.rate_hz = 10.0;
  co.latency_ms = std::round(r.uniform(30.0, 70.0));
  co.latency_jitter_ms = std::round(r.uniform(5.0, 10.0));
  co.vel_sigma_mps = r.uniform(0.02, 0.08);
  co.dependent = false;
  co.range_rate_hz = 10.0;
  co.range_offset_ms = r.uniform(1.0, 9.0);
  co.box_m[0] = 4.5;
  co.box_m[1] = 1.8;
  co.box_m[2] = 1.5;
  co.nlos_bias_min_m = 0.2;
  co.nlos_bias_max_m = 1.5;
  co.nlos_extra_sigma_m = r.uniform(0.1, 0.2);
}

void draw_scenario(const CellSpec& c, uint64_t seed, const FamilyOptions& opt, Scenario& s) {
  Rng r(mix_seed(name_hash(c.name), seed, 0x46414D49ULL));  // "FAMI"
  s = Scenario{};
  s.name = std::string(c.name) + "_" + std::to_string(seed);

  // Sub-kind of the outage cell: parking drive, long straight or multicopter.
  CellKind kind = c.kind;
  bool road = false;
  if (kind == CellKind::kOutage) {
    const double u = r.uniform();
    kind = u < 0.75 ? CellKind::kGround : CellKind::kAir;
    road = u < 0.35;
  } else if (kind == CellKind::kGround) {
    road = r.uniform() < c.road_prob;
  } else if (kind == CellKind::kGnss || kind == CellKind::kCoop) {
    road = true;
  }
  const bool air = kind == CellKind::kAir;
  const bool trolley = kind == CellKind::kTrolley;

  double duration = std::round(draw(r, c.duration_s));
  if (opt.fast) {
    const double cap = c.block_anchors > 0 || c.kind == CellKind::kGnss ? 150.0
                       : c.kind == CellKind::kOutage                   ? 100.0
                                                                       : 60.0;
    duration = std::min(duration, cap);
  }
  s.duration_s = duration;
  s.platform = air ? "air" : "ground";

  // Site and route.
  Area area;
  Canyon canyon;
  const int n_anchors = draw_int(r, c.anchors_min, c.anchors_max);
  if (air) {
    area = Area{0.0, 0.0, r.uniform(8.0, 15.0), r.uniform(6.0, 12.0)};
    place_anchors(r, n_anchors, area, -0.2, 0.0, 0.0, s.anchors);
    for (AnchorDef& a : s.anchors) a.pos_nav_m[2] = r.uniform(0.4, 2.9);
    s.tags.push_back(TagDef{0, {r.uniform(-0.15, 0.15), r.uniform(-0.15, 0.15), r.uniform(-0.1, 0.1)}});
    plan_air(r, area, c.kind == CellKind::kOutage ? Span{0.3, 2.0} : c.speed_mps, duration, s.route);
  } else if (trolley) {
    area = Area{0.0, 0.0, r.uniform(10.0, 25.0), r.uniform(8.0, 15.0)};
    place_anchors(r, n_anchors, area, r.uniform(0.2, 1.0), 1.04, 0.0, s.anchors);
    const double zt = r.uniform(1.0, 1.1);
    s.tags.push_back(TagDef{0, {0.17, 0.0, zt}});
    s.tags.push_back(TagDef{1, {-0.085, 0.15, zt}});
    s.tags.push_back(TagDef{2, {-0.085, -0.15, zt}});
    s.vehicle.roll_gain_deg_per_mps2 = 0.0;
    s.vehicle.pitch_gain_deg_per_mps2 = 0.0;
    plan_ground(r, area, draw(r, c.speed_mps), duration, false, true, s.route);
  } else if (kind == CellKind::kGnss) {
    // Out and back on a road long enough to leave the anchors' coverage for
    // >= 20 s at cruise speed, short enough to come back before the end: one
    // round trip within 90 % of the time left after parking, turns and stops.
    const double v_cruise = draw(r, c.speed_mps);
    const double len_max = std::min(600.0, 16.0 + 0.45 * v_cruise * (duration - 39.0));
    area = Area{0.0, 0.0, r.uniform(350.0, std::max(350.0, len_max)), r.uniform(15.0, 25.0)};
    const Area zone{0.0, 0.0, r.uniform(50.0, 80.0), area.h()};
    const double base_h = draw(r, c.anchor_height_m);
    const double spread = draw(r, c.anchor_spread_m);
    place_road_anchors(r, n_anchors, zone, r.uniform(1.0, 5.0), base_h, spread, s.anchors);
    s.tags.push_back(TagDef{0, {r.uniform(0.0, 1.0), 0.0, r.uniform(1.4, 2.0)}});
    plan_ground(r, area, v_cruise, duration, true, false, s.route);
  } else if (kind == CellKind::kCoop) {
    canyon = plan_canyon(r, c, n_anchors, opt, s);
    area = canyon.street;
    duration = s.duration_s;
  } else {
    area = road ? Area{0.0, 0.0, r.uniform(150.0, 300.0), r.uniform(15.0, 25.0)}
                : Area{0.0, 0.0, r.uniform(30.0, 120.0), r.uniform(20.0, 60.0)};
    const double base_h = draw(r, c.anchor_height_m);
    const double spread = draw(r, c.anchor_spread_m);
    if (road) {
      place_road_anchors(r, n_anchors, area, r.uniform(1.0, 8.0), base_h, spread, s.anchors);
    } else {
      place_anchors(r, n_anchors, area, r.uniform(1.0, 8.0), base_h, spread, s.anchors);
    }
    s.tags.push_back(TagDef{0, {r.uniform(0.0, 1.0), 0.0, r.uniform(1.4, 2.0)}});
    plan_ground(r, area, draw(r, c.speed_mps), duration, road, false, s.route);
  }

  // IMU.
  if (trolley) {
    s.imu.enabled = false;
  } else {
    draw_imu(r, c, s.imu, air);
    s.imu.rate_hz = air ? 200.0 : 100.0;  // flight controllers sample faster
  }

  // Ranging.
  UwbConfig& u = s.uwb;
  if (trolley) {
    u.schedule = UwbSchedule::kFrame;
    u.rate_hz = draw(r, c.rate_hz);
    u.range_lsb_m = 0.01;
    for (const AnchorDef& a : s.anchors) {
      for (const TagDef& t : s.tags) {
        u.pair_offsets.push_back(RangeOffset{a.id, t.id, (r.uniform() < 0.5 ? -1.0 : 1.0) * r.uniform(0.1, 0.3)});
      }
    }
  } else if (c.total_rate_hz > 0.0) {
    u.schedule = UwbSchedule::kRoundRobin;
    const double period_us = std::round(1e6 / (c.total_rate_hz * r.uniform(0.7, 1.4)));
    u.rate_hz = 1e6 / period_us;
  } else {
    u.schedule = UwbSchedule::kPerAnchor;
    u.rate_hz = std::round(draw_log(r, c.rate_hz) * 10.0) / 10.0;
  }
  u.offset_ms = r.uniform(0.5, 2.5) * std::min(1.0, 1e3 / (u.rate_hz * (u.schedule == UwbSchedule::kPerAnchor ? n_anchors : 1) * 4.0));
  u.sigma_m = draw(r, c.sigma_m);
  u.packet_loss = draw(r, c.packet_loss);
  u.burst_loss = draw(r, c.burst_loss);
  u.burst_mean_len = draw_log(r, c.burst_len);
  const double scale_common = draw(r, c.scale_pct) * (r.uniform() < 0.5 ? -1.0 : 1.0);
  u.scale_common_pct = scale_common;
  u.scale_pair_sigma_pct = r.uniform(0.0, c.scale_pct.hi / 3.0);
  u.anchor_offset_sigma_m = draw(r, c.offset_sigma_m);
  s.site.survey_sigma_m = draw(r, c.survey_sigma_m);
  if (c.block_anchors > 0) {
    u.block_anchors = c.block_anchors;
    u.block_min_s = 5.0;
    u.block_max_s = 20.0;
    u.block_gap_min_s = 5.0;
    u.block_gap_max_s = 30.0;
  }
  if (c.kind == CellKind::kOutage) {
    static const double kLengths[] = {5.0, 10.0, 15.0, 30.0};
    double t0 = r.uniform(40.0, 60.0);
    while (true) {
      const double len = kLengths[r.below(4)];
      if (t0 + len > duration - 10.0) break;
      u.outages.push_back(Outage{t0, t0 + len});
      t0 += len + r.uniform(20.0, 40.0);
    }
  }

  // NLOS.
  NlosConfig& nl = s.nlos;
  nl.body_block = !air && !trolley && r.uniform() < c.body_block_prob;
  place_boxes(r, air || trolley ? 0 : draw_int(r, c.boxes_min, c.boxes_max), area, nl.boxes);
  nl.outlier_prob = draw(r, c.outlier_prob);
  nl.episode_share = draw(r, c.episode_share);
  nl.episode_mean_s = draw_log(r, c.episode_mean_s);
  nl.episode_length_law = r.uniform() < 0.5 ? RandomLaw::kExponential : RandomLaw::kLogNormal;
  nl.episode_bias_mean_m = draw(r, c.episode_bias_m);
  nl.episode_bias_law = r.uniform() < 0.5 ? RandomLaw::kExponential : RandomLaw::kLogNormal;

  if (c.kind == CellKind::kGnss) draw_gnss(r, duration, s);
  if (c.kind == CellKind::kCoop) draw_coop(r, canyon, s);

  // Suspension of a car or van: nose-down pitch per m/s^2 of braking, stiff to
  // soft (1-5 deg/g). Own stream, so that the drive's other draws do not
  // depend on it.
  if (!air && !trolley) {
    Rng rs(mix_seed(name_hash(c.name), seed, 0x53555350ULL));  // "SUSP"
    s.vehicle.pitch_gain_deg_per_mps2 = rs.uniform(0.1, 0.5);
  }

  s.description = std::string(c.name) + " seed " + std::to_string(seed) + ": " + (air ? "multicopter" : trolley ? "trolley" : road ? "road" : "lot") +
                  " " + fmt(area.w()) + "x" + fmt(area.h()) + " m, " + std::to_string(n_anchors) + " anchors, " +
                  fmt(u.rate_hz) + (u.schedule == UwbSchedule::kRoundRobin ? " Hz total" : u.schedule == UwbSchedule::kFrame ? " Hz frames" : " Hz per anchor") +
                  ", sigma " + fmt(u.sigma_m) + " m, NLOS episodes " + fmt(100.0 * nl.episode_share) + " %" +
                  (nl.body_block ? ", body NLOS" : "") + ", " + std::to_string(nl.boxes.size()) + " boxes, " +
                  (s.imu.enabled ? "IMU " + fmt(s.imu.accel_noise_ug_per_sqrt_hz) + " ug/rtHz" : std::string("no IMU")) +
                  ", " + std::to_string(u.outages.size()) + " outages";
  if (s.gnss.enabled) {
    size_t blocked = 0;
    for (const GnssWindow& w : s.gnss.windows) blocked += w.kind == GnssWindowKind::kBlocked ? 1U : 0U;
    s.description += ", UWB range " + fmt(u.max_range_m) + " m, GNSS sigma " + fmt(s.gnss.sigma_h_m) +
                     " m (claimed x" + fmt(s.gnss.claim_ratio) + "), latency " + fmt(s.gnss.latency_ms) + " ms, " +
                     std::to_string(blocked) + " blocked + " + std::to_string(s.gnss.windows.size() - blocked) +
                     " multipath windows";
  }
  if (!s.coop.vehicles.empty()) {
    s.description += ", " + fmt(canyon.v_cruise_mps) + " m/s, " + std::to_string(s.coop.vehicles.size()) +
                     " neighbours (";
    for (size_t i = 0; i < s.coop.vehicles.size(); ++i) {
      const NeighbourDef& n = s.coop.vehicles[i];
      s.description += i > 0 ? ", " : "";
      s.description += n.motion == NeighbourMotion::kRoute ? std::string("oncoming")
                       : std::fabs(n.offset_m[1]) > 1.0   ? "next lane " + fmt(n.offset_m[0]) + " m"
                                                          : fmt(n.offset_m[0]) + " m";
    }
    s.description += ")";
  }
  snap_to_recording_precision(s);
}

const CellSpec* find_spec(const std::string& name) {
  for (const CellSpec& c : specs()) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

}  // namespace

const std::vector<FamilyCell>& family_cells() {
  static const std::vector<FamilyCell> cells = [] {
    std::vector<FamilyCell> v;
    for (const CellSpec& c : specs()) v.push_back(FamilyCell{c.name, c.description});
    return v;
  }();
  return cells;
}

Status draw_family_scenario(const std::string& cell, uint64_t seed, const FamilyOptions& options, Scenario& out,
                            std::string* error) {
  const CellSpec* c = find_spec(cell);
  if (c == nullptr) {
    if (error != nullptr) *error = "unknown family cell '" + cell + "' (uwbnav sim --list)";
    return Status::kNotFound;
  }
  draw_scenario(*c, seed, options, out);
  return validate_scenario(out, error);
}

Status simulate_family(const std::string& cell, uint64_t seed, const FamilyOptions& options, SimOutput& out,
                       std::string* error) {
  Scenario sc;
  const Status st = draw_family_scenario(cell, seed, options, sc, error);
  if (!ok(st)) return st;
  SimOptions so;
  so.seed = mix_seed(name_hash(cell), seed, 1);
  const Status sim = simulate_scenario(sc, so, out, error);
  if (!ok(sim)) return sim;
  out.rec.meta["sim_family"] = cell + ":" + std::to_string(seed);
  return Status::kOk;
}

bool parse_family_spec(const std::string& spec, std::string& cell, uint64_t& seed) {
  const std::string prefix = "family:";
  if (spec.rfind(prefix, 0) != 0) return false;
  const size_t colon = spec.find(':', prefix.size());
  if (colon == std::string::npos || colon == prefix.size() || colon + 1 >= spec.size()) return false;
  const std::string num = spec.substr(colon + 1);
  char* end = nullptr;
  const unsigned long long v = std::strtoull(num.c_str(), &end, 10);
  if (*end != '\0' || num[0] == '-') return false;
  cell = spec.substr(prefix.size(), colon - prefix.size());
  seed = v;
  return true;
}

}  // namespace uwbnav::sim
