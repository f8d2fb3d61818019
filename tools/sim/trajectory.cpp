// Truth trajectory: analytic smooth maneuver profiles, horizontal position by
// 3-point Gauss-Legendre quadrature, suspension attitude, exact IMU quantities;
// multicopter: analytic 3-D profiles, thrust-aligned attitude.
#include "tools/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace uwbnav::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Smooth step S(u) = u - sin(2 pi u) / (2 pi) on u in [0, 1] and its first two
// derivatives with respect to time for a maneuver of duration T.
struct Shape {
  double s = 0, ds = 0, dds = 0;
};
Shape shape(double tau, double T) {
  const double u = std::min(std::max(tau / T, 0.0), 1.0);
  const double a = 2.0 * kPi * u;
  Shape sh;
  sh.s = u - std::sin(a) / (2.0 * kPi);
  sh.ds = (1.0 - std::cos(a)) / T;
  sh.dds = 2.0 * kPi * std::sin(a) / (T * T);
  return sh;
}

// 7th-order smooth step s(u) = 35u^4 - 84u^5 + 70u^6 - 20u^7: zero velocity,
// acceleration and jerk at both ends, so a multicopter's tilt rate (which
// follows the jerk) is continuous. Derivatives with respect to time for duration T.
Shape shape7(double tau, double T) {
  const double u = std::min(std::max(tau / T, 0.0), 1.0);
  const double w = 1.0 - u;
  Shape sh;
  sh.s = u * u * u * u * (35.0 - 84.0 * u + 70.0 * u * u - 20.0 * u * u * u);
  sh.ds = 140.0 * u * u * u * w * w * w / T;
  sh.dds = 420.0 * u * u * w * w * (1.0 - 2.0 * u) / (T * T);
  return sh;
}

}  // namespace

void Trajectory::build_air(const Scenario& s, double end_s) {
  air_segs_.clear();
  yaw_segs_.clear();
  const double cover_s = end_s + 1.0;
  Eigen::Vector3d p(s.route.start_nav_m[0], s.route.start_nav_m[1], s.route.start_nav_m[2]);
  double t = 0.0;
  size_t idx = 0;
  const std::vector<Maneuver>& mv = s.route.maneuvers;
  while (t < cover_s) {
    AirSegment seg;
    seg.t0_s = t;
    seg.p0 = p;
    if (mv.empty()) {
      seg.dur_s = cover_s - t + 1.0;
    } else {
      const Maneuver& m = mv[idx];
      seg.kind = m.kind;
      seg.dur_s = m.duration_s;
      if (m.kind == ManeuverKind::kGoto) seg.dp = Eigen::Vector3d(m.arg[0], m.arg[1], m.arg[2]) - p;
      if (m.kind == ManeuverKind::kEight) {
        seg.eight_x_m = m.arg[0];
        seg.eight_y_m = m.arg[1];
        seg.eight_rot_rad = m.arg[2] * kDeg;
        seg.eight_loops = m.arg[3];
      }
      ++idx;
      if (idx >= mv.size()) idx = s.route.loop_from;
    }
    p += seg.dp;
    t += seg.dur_s;
    air_segs_.push_back(seg);
  }
  double yaw = s.route.start_heading_deg * kDeg;
  t = 0.0;
  for (const Maneuver& m : s.route.yaw_turns) {
    YawSegment y;
    y.t0_s = t;
    y.dur_s = m.duration_s;
    y.yaw0_rad = yaw;
    y.dyaw_rad = m.value * kDeg;
    yaw += y.dyaw_rad;
    t += y.dur_s;
    yaw_segs_.push_back(y);
  }
  YawSegment last;
  last.t0_s = t;
  last.dur_s = std::max(cover_s - t, 0.0) + 1.0;
  last.yaw0_rad = yaw;
  yaw_segs_.push_back(last);
}

void Trajectory::air_motion(double t_s, Eigen::Vector3d& p, Eigen::Vector3d& v, Eigen::Vector3d& a) const {
  auto it = std::upper_bound(air_segs_.begin(), air_segs_.end(), t_s,
                             [](double t, const AirSegment& sg) { return t < sg.t0_s; });
  const AirSegment& sg = it == air_segs_.begin() ? air_segs_.front() : *(it - 1);
  const Shape sh = shape7(t_s - sg.t0_s, sg.dur_s);
  p = sg.p0;
  v.setZero();
  a.setZero();
  if (sg.kind == ManeuverKind::kGoto) {
    p += sg.dp * sh.s;
    v = sg.dp * sh.ds;
    a = sg.dp * sh.dds;
  } else if (sg.kind == ManeuverKind::kEight) {
    // Lissajous 1:2 figure-eight, phase phi = 2 pi loops s(u): starts and ends at rest at p0.
    const double k = 2.0 * kPi * sg.eight_loops;
    const double ph = k * sh.s, dph = k * sh.ds, ddph = k * sh.dds;
    const double A = sg.eight_x_m, B = sg.eight_y_m;
    const double x = A * std::sin(ph), y = B * std::sin(2.0 * ph);
    const double vx = A * std::cos(ph) * dph, vy = 2.0 * B * std::cos(2.0 * ph) * dph;
    const double ax = A * (-std::sin(ph) * dph * dph + std::cos(ph) * ddph);
    const double ay = 2.0 * B * (-2.0 * std::sin(2.0 * ph) * dph * dph + std::cos(2.0 * ph) * ddph);
    const double c = std::cos(sg.eight_rot_rad), s = std::sin(sg.eight_rot_rad);
    p += Eigen::Vector3d(c * x - s * y, s * x + c * y, 0.0);
    v = Eigen::Vector3d(c * vx - s * vy, s * vx + c * vy, 0.0);
    a = Eigen::Vector3d(c * ax - s * ay, s * ax + c * ay, 0.0);
  }
}

double Trajectory::air_yaw(double t_s, double* yaw_rate) const {
  auto it = std::upper_bound(yaw_segs_.begin(), yaw_segs_.end(), t_s,
                             [](double t, const YawSegment& sg) { return t < sg.t0_s; });
  const YawSegment& sg = it == yaw_segs_.begin() ? yaw_segs_.front() : *(it - 1);
  const Shape sh = shape7(t_s - sg.t0_s, sg.dur_s);
  if (yaw_rate != nullptr) *yaw_rate = sg.dyaw_rad * sh.ds;
  return sg.yaw0_rad + sg.dyaw_rad * sh.s;
}

Eigen::Matrix3d Trajectory::air_attitude(double t_s) const {
  Eigen::Vector3d p, v, a;
  air_motion(t_s, p, v, a);
  const Eigen::Vector3d f = a + Eigen::Vector3d(0.0, 0.0, gravity_mps2_);
  const Eigen::Vector3d zb = f.normalized();
  const double yaw = air_yaw(t_s, nullptr);
  const Eigen::Vector3d xc(std::cos(yaw), std::sin(yaw), 0.0);
  const Eigen::Vector3d yb = zb.cross(xc).normalized();
  const Eigen::Vector3d xb = yb.cross(zb);
  Eigen::Matrix3d R;
  R.col(0) = xb;
  R.col(1) = yb;
  R.col(2) = zb;
  return R;
}

KinState Trajectory::at_air(uint64_t t_us) const {
  const double t_s = static_cast<double>(t_us) * 1e-6;
  KinState st;
  air_motion(t_s, st.pos_nav_m, st.vel_nav_mps, st.acc_nav_mps2);
  st.R_nav_body = air_attitude(t_s);
  st.q_nav_body = Eigen::Quaterniond(st.R_nav_body).normalized();
  // Body rate from the central difference of the attitude, omega^ = R^T dR/dt
  // (skew part); h = 0.1 ms keeps the truncation error near 1e-9 rad/s.
  constexpr double kH = 1e-4;
  const Eigen::Matrix3d Om = st.R_nav_body.transpose() * (air_attitude(t_s + kH) - air_attitude(t_s - kH)) / (2.0 * kH);
  st.gyro_body_radps = Eigen::Vector3d(0.5 * (Om(2, 1) - Om(1, 2)), 0.5 * (Om(0, 2) - Om(2, 0)), 0.5 * (Om(1, 0) - Om(0, 1)));
  st.accel_body_mps2 = st.R_nav_body.transpose() * (st.acc_nav_mps2 + Eigen::Vector3d(0.0, 0.0, gravity_mps2_));
  const Eigen::Matrix3d& R = st.R_nav_body;
  st.yaw_rad = std::atan2(R(1, 0), R(0, 0));
  st.pitch_rad = std::asin(std::min(1.0, std::max(-1.0, -R(2, 0))));
  st.roll_rad = std::atan2(R(2, 1), R(2, 2));
  st.speed_mps = st.vel_nav_mps.norm();
  return st;
}

void Trajectory::build(const Scenario& s, double end_s) {
  kind_ = s.route.kind;
  gravity_mps2_ = s.gravity_mps2;
  if (kind_ == RouteKind::kMulticopter) {
    build_air(s, end_s);
    return;
  }
  roll_gain_rad_per_mps2_ = s.vehicle.roll_gain_deg_per_mps2 * kDeg;
  pitch_gain_rad_per_mps2_ = s.vehicle.pitch_gain_deg_per_mps2 * kDeg;
  gravity_mps2_ = s.gravity_mps2;
  segs_.clear();
  const double cover_s = end_s + 1.0;
  double t = 0.0;
  double v = 0.0;
  double yaw = s.route.start_heading_deg * kDeg;
  double z = s.route.start_nav_m[2];
  size_t idx = 0;
  const std::vector<Maneuver>& mv = s.route.maneuvers;
  while (t < cover_s) {
    Segment seg;
    seg.t0_s = t;
    seg.v0_mps = v;
    seg.yaw0_rad = yaw;
    seg.z0_m = z;
    if (mv.empty()) {
      seg.kind = ManeuverKind::kHold;
      seg.dur_s = cover_s - t + 1.0;
    } else {
      const Maneuver& m = mv[idx];
      seg.kind = m.kind;
      seg.dur_s = m.duration_s;
      switch (m.kind) {
        case ManeuverKind::kHold: break;
        case ManeuverKind::kSpeed: seg.dv_mps = m.value - v; break;
        case ManeuverKind::kTurn: seg.dyaw_rad = m.value * kDeg; break;
        case ManeuverKind::kClimb: seg.dz_m = m.value; break;
        case ManeuverKind::kGoto:   // multicopter only (validate_scenario)
        case ManeuverKind::kEight: break;
      }
      ++idx;
      if (idx >= mv.size()) idx = s.route.loop_from;
    }
    v += seg.dv_mps;
    yaw += seg.dyaw_rad;
    z += seg.dz_m;
    t += seg.dur_s;
    segs_.push_back(seg);
  }

  const uint64_t end_us = static_cast<uint64_t>(std::ceil(end_s * 1e6)) + kGridUs;
  const size_t n = static_cast<size_t>(end_us / kGridUs) + 2;
  grid_xy_.assign(n, Eigen::Vector2d::Zero());
  grid_xy_[0] = Eigen::Vector2d(s.route.start_nav_m[0], s.route.start_nav_m[1]);
  for (size_t k = 1; k < n; ++k) {
    grid_xy_[k] = grid_xy_[k - 1] + integrate_xy((k - 1) * kGridUs, k * kGridUs);
  }
}

Trajectory::Motion Trajectory::motion(double t_s) const {
  // Last segment starting at or before t (segments cover [0, end + 1 s]).
  auto it = std::upper_bound(segs_.begin(), segs_.end(), t_s,
                             [](double t, const Segment& sg) { return t < sg.t0_s; });
  const Segment& sg = it == segs_.begin() ? segs_.front() : *(it - 1);
  const double tau = t_s - sg.t0_s;
  const Shape sh = shape(tau, sg.dur_s);
  Motion m;
  m.v = sg.v0_mps + sg.dv_mps * sh.s;
  m.a_lon = sg.dv_mps * sh.ds;
  m.jerk = sg.dv_mps * sh.dds;
  m.yaw = sg.yaw0_rad + sg.dyaw_rad * sh.s;
  m.yaw_rate = sg.dyaw_rad * sh.ds;
  m.yaw_acc = sg.dyaw_rad * sh.dds;
  m.z = sg.z0_m + sg.dz_m * sh.s;
  m.vz = sg.dz_m * sh.ds;
  m.az = sg.dz_m * sh.dds;
  return m;
}

Eigen::Vector2d Trajectory::integrate_xy(uint64_t t0_us, uint64_t t1_us) const {
  // Gauss-Legendre 3-point rule on sub-steps of at most kStepUs.
  static const double kNode = std::sqrt(3.0 / 5.0);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  uint64_t a_us = t0_us;
  while (a_us < t1_us) {
    const uint64_t b_us = std::min(a_us + kStepUs, t1_us);
    const double a = static_cast<double>(a_us) * 1e-6;
    const double h = static_cast<double>(b_us - a_us) * 1e-6;
    const double c = a + 0.5 * h;
    const double nodes[3] = {c - 0.5 * h * kNode, c, c + 0.5 * h * kNode};
    const double weights[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
    for (int i = 0; i < 3; ++i) {
      const Motion m = motion(nodes[i]);
      sum += weights[i] * h * m.v * Eigen::Vector2d(std::cos(m.yaw), std::sin(m.yaw));
    }
    a_us = b_us;
  }
  return sum;
}

KinState Trajectory::at(uint64_t t_us) const {
  if (kind_ == RouteKind::kMulticopter) return at_air(t_us);
  const size_t k = std::min(static_cast<size_t>(t_us / kGridUs), grid_xy_.size() - 1);
  const Eigen::Vector2d xy = grid_xy_[k] + integrate_xy(k * kGridUs, t_us);
  const Motion m = motion(static_cast<double>(t_us) * 1e-6);
  const double cy = std::cos(m.yaw);
  const double sy = std::sin(m.yaw);

  KinState st;
  st.pos_nav_m = Eigen::Vector3d(xy.x(), xy.y(), m.z);
  st.vel_nav_mps = Eigen::Vector3d(m.v * cy, m.v * sy, m.vz);
  st.acc_nav_mps2 = Eigen::Vector3d(m.a_lon * cy - m.v * m.yaw_rate * sy, m.a_lon * sy + m.v * m.yaw_rate * cy, m.az);

  // Suspension: roll outward proportional to lateral acceleration, nose dips
  // when braking (pitch about +y positive = nose down in FLU).
  const double a_lat = m.v * m.yaw_rate;
  const double a_lat_rate = m.a_lon * m.yaw_rate + m.v * m.yaw_acc;
  const double roll = roll_gain_rad_per_mps2_ * a_lat;
  const double roll_rate = roll_gain_rad_per_mps2_ * a_lat_rate;
  const double pitch = -pitch_gain_rad_per_mps2_ * m.a_lon;
  const double pitch_rate = -pitch_gain_rad_per_mps2_ * m.jerk;

  st.q_nav_body = Eigen::AngleAxisd(m.yaw, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  st.R_nav_body = st.q_nav_body.toRotationMatrix();

  // Euler ZYX rates -> body rates.
  const double sr = std::sin(roll), cr = std::cos(roll);
  const double sp = std::sin(pitch), cp = std::cos(pitch);
  st.gyro_body_radps = Eigen::Vector3d(roll_rate - m.yaw_rate * sp, pitch_rate * cr + m.yaw_rate * cp * sr,
                                       -pitch_rate * sr + m.yaw_rate * cp * cr);
  // Specific force f = R^T (a - g_nav), g_nav = (0, 0, -g).
  st.accel_body_mps2 =
      st.R_nav_body.transpose() * (st.acc_nav_mps2 + Eigen::Vector3d(0.0, 0.0, gravity_mps2_));
  st.roll_rad = roll;
  st.pitch_rad = pitch;
  st.yaw_rad = m.yaw;
  st.speed_mps = m.v;
  return st;
}

bool segment_hits_box(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Box& box) {
  double t_min = 0.0;
  double t_max = 1.0;
  for (int i = 0; i < 3; ++i) {
    const double d = q[i] - p[i];
    if (std::fabs(d) < 1e-12) {
      if (p[i] < box.min_nav_m[i] || p[i] > box.max_nav_m[i]) return false;
      continue;
    }
    double t0 = (box.min_nav_m[i] - p[i]) / d;
    double t1 = (box.max_nav_m[i] - p[i]) / d;
    if (t0 > t1) std::swap(t0, t1);
    t_min = std::max(t_min, t0);
    t_max = std::min(t_max, t1);
    if (t_min > t_max) return false;
  }
  return true;
}

}  // namespace uwbnav::sim
