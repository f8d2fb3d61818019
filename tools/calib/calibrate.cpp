// Batch robust least-squares calibration of per-pair range offsets (see
// calibrate.hpp and docs/commissioning.md for the model, the gauge and the
// uncertainty).
#include "tools/calib/calibrate.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace uwbnav::calib {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr size_t kMinRangesPerPair = 20;   // fewer used ranges: the pair is not calibrated
constexpr double kScaleFloorM = 1e-3;      // robust scale floor (noise-free simulations) [m]
constexpr double kKnotPriorInfo = 1e-6;    // weak absolute prior on knot states (sigma 1 km / 1 krad)
constexpr double kMaxRho = 0.95;           // AR(1) coefficient cap
constexpr double kBlockS = 5.0;            // batch-means block length [s]
constexpr size_t kMinBlocks = 5;           // fewer blocks: no batch-means estimate
constexpr double kBodyZPriorSigmaM = 2.0;  // self, common height: prior 1-sigma around --body-z [m]
constexpr double kGaugeSigmaM = 1e-5;      // --common-offset: how tightly the mean offset is held [m]

using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;

struct Obs {
  double t_s = 0.0;       // time since the recording's first range [s]
  uint32_t pair = 0;      // anchor index * num_tags + tag index
  uint32_t tag = 0;       // tag index
  uint32_t rec = 0;       // recording index
  double anchor[3] = {0, 0, 0};
  double range_m = 0.0;
  int32_t k0 = -1;        // knot of the tag position; -1: tag_nav is known
  int32_t k1 = -1;        // second knot (linear interpolation) or -1
  double w1 = 0.0;        // interpolation weight of k1
  double tag_nav[3] = {0, 0, 0};
  double resid = 0.0;     // measured minus modelled range [m]
  double weight = 0.0;    // robust weight in [0, 1]
};

struct Knot {
  double t_s = 0.0;
  double s[4] = {0, 0, 0, 0};  // body origin x, y, z [m] and yaw [rad] (z unused with a common height)
  bool free[4] = {false, false, false, false};
  int32_t col[4] = {-1, -1, -1, -1};
  uint32_t rec = 0;
  uint32_t seg = 0;            // knots of one segment are chained by the motion prior
  bool initialised = false;
};

double wrap_pi(double a) {
  while (a > kPi) a -= 2.0 * kPi;
  while (a < -kPi) a += 2.0 * kPi;
  return a;
}

double median_of(std::vector<double>& v) {
  if (v.empty()) return 0.0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}

// Body-frame lever arm rotated into the navigation frame with a quaternion (body -> nav).
void rotate(const double q[4], const Vec3f& l, double out[3]) {
  const Eigen::Quaterniond qq(q[0], q[1], q[2], q[3]);
  const Eigen::Vector3d v =
      qq.normalized() * Eigen::Vector3d(static_cast<double>(l.x), static_cast<double>(l.y), static_cast<double>(l.z));
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}

class Solver {
 public:
  Solver(const std::vector<dataset::Recording>& recs, const Options& opt, Result& res)
      : recs_(recs), opt_(opt), res_(res), site_(recs.front().site) {}

  Status run(std::string* error);

 private:
  Status build_truth(std::string* error);
  Status build_static(std::string* error);
  Status build_self(std::string* error);
  bool pair_of(const UwbRange& r, uint32_t& pair, uint32_t& tag) const;
  void tag_position(const Knot& k, uint32_t tag, double out[3], double dyaw[3]) const;
  double body_z(const Knot& k) const;
  void model(const Obs& o, double& h, double u[3], double xt[3]) const;
  void init_knot_pose(size_t k, const std::vector<size_t>& obs_idx, bool have_start);
  double pose_cost(const Knot& k, const std::vector<size_t>& obs_idx) const;
  void assign_columns();
  void evaluate();
  void build_normal(Eigen::SparseMatrix<double>& h, Eigen::VectorXd& rhs);
  double cost() const;
  void apply(const Eigen::VectorXd& d, double& max_offset, double& max_state);
  void finish(const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& ldlt);
  void decompose();
  void describe_weak(const Eigen::MatrixXd& cov);

  const std::vector<dataset::Recording>& recs_;
  const Options& opt_;
  Result& res_;
  const SiteConfig& site_;
  size_t np_ = 0;                 // pairs
  size_t ng_ = 0;                 // global columns: offsets, then common heights
  size_t ncols_ = 0;
  std::vector<double> offset_;    // per pair [m]
  std::vector<double> zg_;        // per recording common body-origin height [m]
  std::vector<int32_t> zcol_;     // its column, -1 when not estimated
  std::vector<double> scale_;     // per pair robust scale [m]
  std::vector<Obs> obs_;
  std::vector<Knot> knots_;
  std::vector<uint64_t> t0_us_;   // per recording: time origin of Obs::t_s
  bool yaw_free_ = false;
  double knot_s_ = 0.1;           // knot spacing in use [s]
};

bool Solver::pair_of(const UwbRange& r, uint32_t& pair, uint32_t& tag) const {
  const int a = site_.find_anchor(r.anchor_id);
  const int t = site_.find_tag(r.tag_id);
  if (a < 0 || t < 0) return false;
  tag = static_cast<uint32_t>(t);
  pair = static_cast<uint32_t>(static_cast<size_t>(a) * site_.num_tags + static_cast<size_t>(t));
  return true;
}

double Solver::body_z(const Knot& k) const {
  return zcol_.empty() || zcol_[k.rec] < 0 ? k.s[2] : zg_[k.rec];
}

// Tag antenna of a level vehicle at knot state k; dyaw = d(position)/d(yaw).
void Solver::tag_position(const Knot& k, uint32_t tag, double out[3], double dyaw[3]) const {
  const Vec3f& l = site_.tags[tag].lever_body_m;
  const double lx = l.x;
  const double ly = l.y;
  const double lz = l.z;
  const double c = std::cos(k.s[3]);
  const double s = std::sin(k.s[3]);
  out[0] = k.s[0] + c * lx - s * ly;
  out[1] = k.s[1] + s * lx + c * ly;
  out[2] = body_z(k) + lz;
  dyaw[0] = -s * lx - c * ly;
  dyaw[1] = c * lx - s * ly;
  dyaw[2] = 0.0;
}

void Solver::model(const Obs& o, double& h, double u[3], double xt[3]) const {
  if (o.k0 < 0) {
    for (int i = 0; i < 3; ++i) xt[i] = o.tag_nav[i];
  } else {
    double p0[3];
    double d0[3];
    tag_position(knots_[static_cast<size_t>(o.k0)], o.tag, p0, d0);
    if (o.k1 >= 0) {
      double p1[3];
      double d1[3];
      tag_position(knots_[static_cast<size_t>(o.k1)], o.tag, p1, d1);
      for (int i = 0; i < 3; ++i) xt[i] = (1.0 - o.w1) * p0[i] + o.w1 * p1[i];
    } else {
      for (int i = 0; i < 3; ++i) xt[i] = p0[i];
    }
  }
  double d2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    u[i] = xt[i] - o.anchor[i];
    d2 += u[i] * u[i];
  }
  const double d = std::sqrt(d2);
  for (int i = 0; i < 3; ++i) u[i] = d > 1e-9 ? u[i] / d : 0.0;
  h = d + offset_[o.pair];
}

Status Solver::build_truth(std::string* error) {
  for (uint32_t r = 0; r < recs_.size(); ++r) {
    const dataset::Recording& rec = recs_[r];
    if (rec.truth.size() < 2) {
      if (error) *error = rec.name() + ": no truth.csv (method truth needs reference positions)";
      return Status::kInvalidArgument;
    }
    bool attitude = true;
    for (const auto& t : rec.truth) attitude = attitude && t.has_attitude;
    if (!attitude) {
      for (size_t j = 0; j < site_.num_tags; ++j) {
        const Vec3f& l = site_.tags[j].lever_body_m;
        if (l.x != 0.0F || l.y != 0.0F) {
          if (error) {
            *error = rec.name() + ": truth.csv has no attitude (qw,qx,qy,qz) but tag " +
                     std::to_string(site_.tags[j].id) +
                     " has a horizontal lever arm: give a truth with attitude, static points with yaw, or use --method self";
          }
          return Status::kInvalidArgument;
        }
      }
      res_.notes.push_back(rec.name() + ": truth without attitude; tags are directly above the body origin (level body assumed)");
    }
    const uint64_t max_gap_us = static_cast<uint64_t>(opt_.max_truth_gap_s * 1e6);
    size_t j = 0;
    for (const dataset::UwbRow& row : rec.uwb) {
      ++res_.ranges_total;
      Obs o;
      if (!pair_of(row.range, o.pair, o.tag)) {
        ++res_.ranges_unknown;
        continue;
      }
      const uint64_t t = row.range.t_us;
      while (j + 1 < rec.truth.size() && rec.truth[j + 1].t_us < t) ++j;
      if (j + 1 >= rec.truth.size() || rec.truth[j].t_us > t || rec.truth[j + 1].t_us - rec.truth[j].t_us > max_gap_us) {
        ++res_.ranges_no_reference;
        continue;
      }
      const dataset::TruthRow& a = rec.truth[j];
      const dataset::TruthRow& b = rec.truth[j + 1];
      const double span = static_cast<double>(b.t_us - a.t_us);
      const double w = span > 0.0 ? static_cast<double>(t - a.t_us) / span : 0.0;
      double pos[3];
      for (int i = 0; i < 3; ++i) pos[i] = (1.0 - w) * a.pos_nav_m[i] + w * b.pos_nav_m[i];
      double lever[3];
      const Vec3f& l = site_.tags[o.tag].lever_body_m;
      if (attitude) {
        double dot = 0.0;
        for (int i = 0; i < 4; ++i) dot += a.q_nav_body[i] * b.q_nav_body[i];
        const double sgn = dot < 0.0 ? -1.0 : 1.0;
        double q[4];
        for (int i = 0; i < 4; ++i) q[i] = (1.0 - w) * a.q_nav_body[i] + w * sgn * b.q_nav_body[i];
        rotate(q, l, lever);
      } else {
        lever[0] = l.x;
        lever[1] = l.y;
        lever[2] = l.z;
      }
      for (int i = 0; i < 3; ++i) o.tag_nav[i] = pos[i] + lever[i];
      const Vec3f& an = site_.anchors[o.pair / site_.num_tags].pos_nav_m;
      o.anchor[0] = an.x;
      o.anchor[1] = an.y;
      o.anchor[2] = an.z;
      o.range_m = row.range.range_m;
      o.rec = r;
      o.t_s = static_cast<double>(t - t0_us_[r]) * 1e-6;
      obs_.push_back(o);
    }
  }
  return Status::kOk;
}

Status Solver::build_static(std::string* error) {
  if (opt_.static_points.size() != recs_.size()) {
    if (error) *error = "method static needs static points for every recording (static_points.csv or --static-points)";
    return Status::kInvalidArgument;
  }
  for (uint32_t r = 0; r < recs_.size(); ++r) {
    const dataset::Recording& rec = recs_[r];
    const std::vector<StaticPoint>& pts = opt_.static_points[r];
    const size_t first_knot = knots_.size();
    for (const StaticPoint& sp : pts) {
      Knot k;
      k.t_s = 0.0;
      for (int i = 0; i < 3; ++i) k.s[i] = sp.pos_nav_m[i];
      k.s[3] = sp.yaw_rad;
      k.free[3] = !sp.has_yaw;
      k.initialised = sp.has_yaw;
      k.rec = r;
      k.seg = static_cast<uint32_t>(knots_.size());
      if (!sp.has_yaw) {
        bool lever_horizontal = false;
        for (size_t j = 0; j < site_.num_tags; ++j) {
          lever_horizontal = lever_horizontal || site_.tags[j].lever_body_m.x != 0.0F ||
                             site_.tags[j].lever_body_m.y != 0.0F;
        }
        if (!lever_horizontal) {
          k.free[3] = false;  // the tags sit above the body origin: yaw does not matter
          k.initialised = true;
        } else if (site_.num_tags < 2) {
          if (error) {
            *error = rec.name() + ": static point " + sp.id + " (line " + std::to_string(sp.line) +
                     ") has no yaw_deg, and with one tag off the body origin the heading is not observable";
          }
          return Status::kInvalidArgument;
        }
      }
      knots_.push_back(k);
    }
    size_t in_windows = 0;
    for (const dataset::UwbRow& row : rec.uwb) {
      ++res_.ranges_total;
      Obs o;
      if (!pair_of(row.range, o.pair, o.tag)) {
        ++res_.ranges_unknown;
        continue;
      }
      const uint64_t t = row.range.t_us;
      int32_t kk = -1;
      for (size_t i = 0; i < pts.size(); ++i) {
        if (t >= pts[i].t_start_us && t <= pts[i].t_end_us) kk = static_cast<int32_t>(first_knot + i);
      }
      if (kk < 0) {
        ++res_.ranges_no_reference;
        continue;
      }
      ++in_windows;
      const Vec3f& an = site_.anchors[o.pair / site_.num_tags].pos_nav_m;
      o.anchor[0] = an.x;
      o.anchor[1] = an.y;
      o.anchor[2] = an.z;
      o.range_m = row.range.range_m;
      o.rec = r;
      o.k0 = kk;
      o.t_s = static_cast<double>(t - t0_us_[r]) * 1e-6;
      obs_.push_back(o);
    }
    if (in_windows == 0) {
      if (error) *error = rec.name() + ": no range falls inside any static point window";
      return Status::kInvalidArgument;
    }
  }
  for (const Knot& k : knots_) yaw_free_ = yaw_free_ || k.free[3];
  return Status::kOk;
}

// Knots every knot_s over each stretch of ranges (a gap longer than max_gap_s
// starts a new segment); every range is tied to its two neighbouring knots.
Status Solver::build_self(std::string* error) {
  bool lever_horizontal = false;
  for (size_t j = 0; j < site_.num_tags; ++j) {
    lever_horizontal = lever_horizontal || site_.tags[j].lever_body_m.x != 0.0F || site_.tags[j].lever_body_m.y != 0.0F;
  }
  // Yaw is a state when two tags sit at different horizontal places on the body.
  yaw_free_ = false;
  for (size_t a = 0; a < site_.num_tags && !yaw_free_; ++a) {
    for (size_t b = a + 1; b < site_.num_tags; ++b) {
      const Vec3f& la = site_.tags[a].lever_body_m;
      const Vec3f& lb = site_.tags[b].lever_body_m;
      if (std::hypot(la.x - lb.x, la.y - lb.y) > 0.05F) yaw_free_ = true;
    }
  }
  if (lever_horizontal && !yaw_free_) {
    res_.notes.push_back("one tag position on the body: the trajectory is that of the antenna (yaw not estimated)");
  }
  // Knot spacing: as asked, or the shortest (>= 0.1 s) that gives every knot
  // on average 3 ranges per unknown, so the trajectory cannot follow the noise.
  const size_t slots = 2 + (opt_.z == ZMode::kFree ? 1U : 0U) + (yaw_free_ ? 1U : 0U);
  double rate_hz = 0.0;
  for (const dataset::Recording& rec : recs_) {
    if (rec.uwb.size() < 2) continue;
    const double span_s = static_cast<double>(rec.uwb.back().range.t_us - rec.uwb.front().range.t_us) * 1e-6;
    if (span_s > 0.0) rate_hz = std::max(rate_hz, static_cast<double>(rec.uwb.size()) / span_s);
  }
  knot_s_ = opt_.knot_s > 0.0 ? opt_.knot_s
                              : std::max(0.1, rate_hz > 0.0 ? 3.0 * static_cast<double>(slots) / rate_hz : 0.1);
  res_.knot_s = knot_s_;
  const double dt = knot_s_;
  uint32_t seg = 0;
  for (uint32_t r = 0; r < recs_.size(); ++r) {
    const dataset::Recording& rec = recs_[r];
    size_t seg_first_knot = knots_.size();
    double seg_t0 = -1.0;
    double last_t = -1.0;
    for (const dataset::UwbRow& row : rec.uwb) {
      ++res_.ranges_total;
      Obs o;
      if (!pair_of(row.range, o.pair, o.tag)) {
        ++res_.ranges_unknown;
        continue;
      }
      o.t_s = static_cast<double>(row.range.t_us - t0_us_[r]) * 1e-6;
      if (seg_t0 < 0.0 || o.t_s - last_t > opt_.max_gap_s) {
        ++seg;
        seg_t0 = o.t_s;
        seg_first_knot = knots_.size();
      }
      last_t = o.t_s;
      const size_t k = static_cast<size_t>(std::floor((o.t_s - seg_t0) / dt + 1e-9));
      while (knots_.size() < seg_first_knot + k + 2) {
        Knot kn;
        kn.t_s = seg_t0 + static_cast<double>(knots_.size() - seg_first_knot) * dt;
        kn.rec = r;
        kn.seg = seg;
        kn.free[0] = true;
        kn.free[1] = true;
        kn.free[2] = opt_.z == ZMode::kFree;
        kn.free[3] = yaw_free_;
        kn.s[2] = opt_.body_z_m;
        knots_.push_back(kn);
      }
      o.k0 = static_cast<int32_t>(seg_first_knot + k);
      o.k1 = o.k0 + 1;
      o.w1 = (o.t_s - knots_[static_cast<size_t>(o.k0)].t_s) / dt;
      const Vec3f& an = site_.anchors[o.pair / site_.num_tags].pos_nav_m;
      o.anchor[0] = an.x;
      o.anchor[1] = an.y;
      o.anchor[2] = an.z;
      o.range_m = row.range.range_m;
      o.rec = r;
      obs_.push_back(o);
    }
  }
  if (opt_.z == ZMode::kCommon) {
    zcol_.assign(recs_.size(), -1);
    for (size_t r = 0; r < recs_.size(); ++r) zcol_[r] = static_cast<int32_t>(np_ + r);
  }
  if (error != nullptr && knots_.empty()) *error = "no ranges of the site's anchors and tags";
  return knots_.empty() ? Status::kInvalidArgument : Status::kOk;
}

// Robust cost of a knot pose against the ranges near it (offsets as they are).
double Solver::pose_cost(const Knot& k, const std::vector<size_t>& obs_idx) const {
  double c = 0.0;
  for (size_t i : obs_idx) {
    const Obs& o = obs_[i];
    double p[3];
    double dy[3];
    tag_position(k, o.tag, p, dy);
    const double d = std::sqrt((p[0] - o.anchor[0]) * (p[0] - o.anchor[0]) + (p[1] - o.anchor[1]) * (p[1] - o.anchor[1]) +
                               (p[2] - o.anchor[2]) * (p[2] - o.anchor[2]));
    const double e = std::fabs(o.range_m - offset_[o.pair] - d);
    c += e < 0.3 ? 0.5 * e * e : 0.3 * (e - 0.15);  // Huber, 0.3 m
  }
  return c;
}

// Gauss-Newton on one knot's free slots from several yaw starts; keeps the best.
void Solver::init_knot_pose(size_t kidx, const std::vector<size_t>& obs_idx, bool have_start) {
  Knot& k = knots_[kidx];
  if (!have_start) {
    double cx = 0.0;
    double cy = 0.0;
    for (size_t a = 0; a < site_.num_anchors; ++a) {
      cx += static_cast<double>(site_.anchors[a].pos_nav_m.x);
      cy += static_cast<double>(site_.anchors[a].pos_nav_m.y);
    }
    if (k.free[0]) k.s[0] = cx / static_cast<double>(site_.num_anchors);
    if (k.free[1]) k.s[1] = cy / static_cast<double>(site_.num_anchors);
    if (k.free[3]) k.s[3] = 0.0;
  }
  std::vector<double> starts = {k.s[3]};
  if (k.free[3]) {
    if (!have_start) starts.clear();
    const int n = have_start ? 4 : 12;
    for (int i = have_start ? 1 : 0; i < n; ++i) starts.push_back(k.s[3] + 2.0 * kPi * i / n);
  }
  Knot best = k;
  double best_cost = -1.0;
  for (double yaw0 : starts) {
    Knot t = k;
    t.s[3] = yaw0;
    for (int it = 0; it < 15; ++it) {
      Eigen::Matrix4d h = Eigen::Matrix4d::Zero();
      Vec4 g = Vec4::Zero();
      for (size_t i : obs_idx) {
        const Obs& o = obs_[i];
        double p[3];
        double dy[3];
        tag_position(t, o.tag, p, dy);
        double u[3];
        double d2 = 0.0;
        for (int j = 0; j < 3; ++j) {
          u[j] = p[j] - o.anchor[j];
          d2 += u[j] * u[j];
        }
        const double d = std::sqrt(d2);
        if (d < 1e-6) continue;
        for (double& v : u) v /= d;
        const double e = o.range_m - offset_[o.pair] - d;
        const double w = std::fabs(e) < 0.3 ? 1.0 : 0.3 / std::fabs(e);
        Vec4 jr(u[0], u[1], u[2], u[0] * dy[0] + u[1] * dy[1]);
        for (int j = 0; j < 4; ++j) {
          if (!t.free[j]) jr[j] = 0.0;
        }
        h += w * jr * jr.transpose();
        g += w * jr * e;
      }
      for (int j = 0; j < 4; ++j) h(j, j) += t.free[j] ? 1e-6 : 1.0;
      const Vec4 d = h.ldlt().solve(g);
      for (int j = 0; j < 4; ++j) {
        if (t.free[j]) t.s[j] += std::max(-5.0, std::min(5.0, d[j]));
      }
      if (d.head<3>().norm() < 1e-4 && std::fabs(d[3]) < 1e-5) break;
    }
    const double c = pose_cost(t, obs_idx);
    if (std::isfinite(c) && (best_cost < 0.0 || c < best_cost)) {
      best_cost = c;
      best = t;
    }
  }
  best.s[3] = wrap_pi(best.s[3]);
  k = best;
  k.initialised = best_cost >= 0.0;
}

void Solver::assign_columns() {
  ng_ = np_ + (zcol_.empty() ? 0 : recs_.size());
  int32_t c = static_cast<int32_t>(ng_);
  for (Knot& k : knots_) {
    for (int j = 0; j < 4; ++j) k.col[j] = k.free[j] ? c++ : -1;
  }
  ncols_ = static_cast<size_t>(c);
}

// Residuals with the current parameters, per-pair robust scales, IRLS weights.
void Solver::evaluate() {
  std::vector<std::vector<double>> per_pair(np_);
  for (Obs& o : obs_) {
    double h = 0.0;
    double u[3];
    double xt[3];
    model(o, h, u, xt);
    o.resid = o.range_m - h;
    per_pair[o.pair].push_back(o.resid);
  }
  std::vector<double> mads;
  for (size_t p = 0; p < np_; ++p) {
    std::vector<double>& v = per_pair[p];
    if (v.empty()) {
      scale_[p] = 1.0;
      continue;
    }
    const double med = median_of(v);
    for (double& x : v) x = std::fabs(x - med);
    scale_[p] = 1.4826 * median_of(v);
    mads.push_back(scale_[p]);
  }
  // A pair's scale never drops below half the median pair scale: otherwise a
  // free trajectory could fit one pair exactly, whose weight would then grow
  // without bound (self-calibration).
  const double floor_m = std::max(kScaleFloorM, 0.5 * median_of(mads));
  for (size_t p = 0; p < np_; ++p) scale_[p] = std::max(scale_[p], floor_m);
  for (Obs& o : obs_) {
    const double z = std::fabs(o.resid) / scale_[o.pair];
    o.weight = z > opt_.reject_k ? 0.0 : (z > opt_.huber_k ? opt_.huber_k / z : 1.0);
  }
}

void Solver::build_normal(Eigen::SparseMatrix<double>& h, Eigen::VectorXd& rhs) {
  const size_t nk = knots_.size();
  std::vector<Mat4> d(nk, Mat4::Zero());
  std::vector<Mat4> o1(nk, Mat4::Zero());
  std::vector<Mat4> o2(nk, Mat4::Zero());
  std::vector<Vec4> gk(nk, Vec4::Zero());
  std::vector<Eigen::Matrix<double, 4, Eigen::Dynamic>> ck(nk);
  for (auto& c : ck) c = Eigen::Matrix<double, 4, Eigen::Dynamic>::Zero(4, static_cast<Eigen::Index>(ng_));
  Eigen::MatrixXd hg = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(ng_), static_cast<Eigen::Index>(ng_));
  Eigen::VectorXd gg = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ng_));

  for (const Obs& o : obs_) {
    if (o.weight <= 0.0) continue;
    const double w = o.weight / (scale_[o.pair] * scale_[o.pair]);
    double h0 = 0.0;
    double u[3];
    double xt[3];
    model(o, h0, u, xt);
    const double e = o.resid;
    // Global part: the pair offset (1) and a common height (u_z).
    int gi[2] = {static_cast<int>(o.pair), -1};
    double gv[2] = {1.0, 0.0};
    if (o.k0 >= 0 && !zcol_.empty() && zcol_[o.rec] >= 0) {
      gi[1] = zcol_[o.rec];
      gv[1] = u[2];
    }
    for (int a = 0; a < 2; ++a) {
      if (gi[a] < 0) continue;
      gg[gi[a]] += w * gv[a] * e;
      for (int b = 0; b < 2; ++b) {
        if (gi[b] >= 0) hg(gi[a], gi[b]) += w * gv[a] * gv[b];
      }
    }
    if (o.k0 < 0) continue;
    Vec4 jn[2];
    int32_t kn[2] = {o.k0, o.k1};
    double wk[2] = {o.k1 >= 0 ? 1.0 - o.w1 : 1.0, o.w1};
    for (int n = 0; n < 2; ++n) {
      jn[n].setZero();
      if (kn[n] < 0) continue;
      const Knot& k = knots_[static_cast<size_t>(kn[n])];
      double p[3];
      double dy[3];
      tag_position(k, o.tag, p, dy);
      const double full[4] = {u[0], u[1], u[2], u[0] * dy[0] + u[1] * dy[1]};
      for (int j = 0; j < 4; ++j) jn[n][j] = k.free[j] ? wk[n] * full[j] : 0.0;
    }
    for (int n = 0; n < 2; ++n) {
      if (kn[n] < 0) continue;
      const size_t k = static_cast<size_t>(kn[n]);
      d[k] += w * jn[n] * jn[n].transpose();
      gk[k] += w * jn[n] * e;
      for (int a = 0; a < 2; ++a) {
        if (gi[a] >= 0) ck[k].col(gi[a]) += w * jn[n] * gv[a];
      }
    }
    if (kn[1] >= 0) o1[static_cast<size_t>(kn[0])] += w * jn[0] * jn[1].transpose();
  }

  // Priors: offsets around 0; optionally the mean of the offsets fixed (gauge).
  const double q_off = 1.0 / (opt_.prior_sigma_m * opt_.prior_sigma_m);
  for (size_t p = 0; p < np_; ++p) {
    hg(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p)) += q_off;
    gg[static_cast<Eigen::Index>(p)] += q_off * (0.0 - offset_[p]);
  }
  for (size_t r = 0; r < zcol_.size(); ++r) {
    if (zcol_[r] < 0) continue;
    const double q = 1.0 / (kBodyZPriorSigmaM * kBodyZPriorSigmaM);
    hg(zcol_[r], zcol_[r]) += q;
    gg[zcol_[r]] += q * (opt_.body_z_m - zg_[r]);
  }
  if (opt_.fix_common && np_ > 0) {
    const double q = 1.0 / (kGaugeSigmaM * kGaugeSigmaM);
    double mean = 0.0;
    for (double v : offset_) mean += v;
    mean /= static_cast<double>(np_);
    const double inv = 1.0 / static_cast<double>(np_);
    for (size_t a = 0; a < np_; ++a) {
      gg[static_cast<Eigen::Index>(a)] += q * inv * (opt_.common_offset_m - mean);
      for (size_t b = 0; b < np_; ++b) hg(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) += q * inv * inv;
    }
  }
  // Knots: a negligible absolute prior (keeps isolated knots regular) and the
  // random-acceleration prior on second differences within a segment.
  for (size_t k = 0; k < nk; ++k) {
    for (int j = 0; j < 4; ++j) {
      if (knots_[k].free[j]) d[k](j, j) += kKnotPriorInfo;
    }
  }
  const double dt2 = knot_s_ * knot_s_;
  for (size_t k = 1; k + 1 < nk; ++k) {
    const Knot& a = knots_[k - 1];
    const Knot& b = knots_[k];
    const Knot& c = knots_[k + 1];
    if (a.seg != b.seg || b.seg != c.seg || a.col[0] < 0) continue;
    for (int j = 0; j < 4; ++j) {
      if (!b.free[j]) continue;
      const double sig = (j == 3 ? opt_.yaw_accel_sigma_radps2 : opt_.accel_sigma_mps2) * dt2;
      const double q = 1.0 / (sig * sig);
      const double r = -(c.s[j] - 2.0 * b.s[j] + a.s[j]);
      d[k - 1](j, j) += q;
      d[k](j, j) += 4.0 * q;
      d[k + 1](j, j) += q;
      o1[k - 1](j, j) += -2.0 * q;
      o1[k](j, j) += -2.0 * q;
      o2[k - 1](j, j) += q;
      gk[k - 1][j] += q * r;
      gk[k][j] += -2.0 * q * r;
      gk[k + 1][j] += q * r;
    }
  }

  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(ng_ * ng_ + nk * (48 + 8 * 2));
  rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ncols_));
  for (size_t a = 0; a < ng_; ++a) {
    rhs[static_cast<Eigen::Index>(a)] = gg[static_cast<Eigen::Index>(a)];
    for (size_t b = 0; b < ng_; ++b) {
      const double v = hg(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
      if (v != 0.0) trip.emplace_back(static_cast<int>(a), static_cast<int>(b), v);
    }
  }
  auto block = [&](size_t ka, size_t kb, const Mat4& m) {
    for (int i = 0; i < 4; ++i) {
      const int ci = knots_[ka].col[i];
      if (ci < 0) continue;
      for (int j = 0; j < 4; ++j) {
        const int cj = knots_[kb].col[j];
        if (cj < 0 || m(i, j) == 0.0) continue;
        trip.emplace_back(ci, cj, m(i, j));
        if (ka != kb) trip.emplace_back(cj, ci, m(i, j));
      }
    }
  };
  for (size_t k = 0; k < nk; ++k) {
    block(k, k, d[k]);
    if (k + 1 < nk) block(k, k + 1, o1[k]);
    if (k + 2 < nk) block(k, k + 2, o2[k]);
    for (int i = 0; i < 4; ++i) {
      const int ci = knots_[k].col[i];
      if (ci < 0) continue;
      rhs[ci] = gk[k][i];
      for (size_t g = 0; g < ng_; ++g) {
        const double v = ck[k](i, static_cast<Eigen::Index>(g));
        if (v == 0.0) continue;
        trip.emplace_back(ci, static_cast<int>(g), v);
        trip.emplace_back(static_cast<int>(g), ci, v);
      }
    }
  }
  h.resize(static_cast<Eigen::Index>(ncols_), static_cast<Eigen::Index>(ncols_));
  h.setFromTriplets(trip.begin(), trip.end());
}

// The objective the normal equations linearise, with the current IRLS weights
// and scales: weighted squared residuals plus every prior term.
double Solver::cost() const {
  double f = 0.0;
  for (const Obs& o : obs_) {
    if (o.weight <= 0.0) continue;
    double h = 0.0;
    double u[3];
    double xt[3];
    model(o, h, u, xt);
    const double e = o.range_m - h;
    f += o.weight * e * e / (scale_[o.pair] * scale_[o.pair]);
  }
  double mean = 0.0;
  for (double v : offset_) {
    f += v * v / (opt_.prior_sigma_m * opt_.prior_sigma_m);
    mean += v;
  }
  if (opt_.fix_common && np_ > 0) {
    const double d = opt_.common_offset_m - mean / static_cast<double>(np_);
    f += d * d / (kGaugeSigmaM * kGaugeSigmaM);
  }
  for (size_t r = 0; r < zcol_.size(); ++r) {
    if (zcol_[r] >= 0) f += (zg_[r] - opt_.body_z_m) * (zg_[r] - opt_.body_z_m) / (kBodyZPriorSigmaM * kBodyZPriorSigmaM);
  }
  const double dt2 = knot_s_ * knot_s_;
  for (size_t k = 1; k + 1 < knots_.size(); ++k) {
    const Knot& a = knots_[k - 1];
    const Knot& b = knots_[k];
    const Knot& c = knots_[k + 1];
    if (a.seg != b.seg || b.seg != c.seg || a.col[0] < 0) continue;
    for (int j = 0; j < 4; ++j) {
      if (!b.free[j]) continue;
      const double sig = (j == 3 ? opt_.yaw_accel_sigma_radps2 : opt_.accel_sigma_mps2) * dt2;
      const double r = c.s[j] - 2.0 * b.s[j] + a.s[j];
      f += r * r / (sig * sig);
    }
  }
  return f;
}

void Solver::apply(const Eigen::VectorXd& dx, double& max_offset, double& max_state) {
  max_offset = 0.0;
  max_state = 0.0;
  for (size_t p = 0; p < np_; ++p) {
    offset_[p] += dx[static_cast<Eigen::Index>(p)];
    max_offset = std::max(max_offset, std::fabs(dx[static_cast<Eigen::Index>(p)]));
  }
  for (size_t r = 0; r < zcol_.size(); ++r) {
    if (zcol_[r] < 0) continue;
    zg_[r] += dx[zcol_[r]];
    max_state = std::max(max_state, std::fabs(dx[zcol_[r]]));
  }
  for (Knot& k : knots_) {
    for (int j = 0; j < 4; ++j) {
      if (k.col[j] < 0) continue;
      k.s[j] += dx[k.col[j]];
      max_state = std::max(max_state, std::fabs(dx[k.col[j]]));
    }
  }
}

// Offset covariance, AR(1) inflation, per-pair statistics, observability.
void Solver::finish(const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& ldlt) {
  const Eigen::Index n = static_cast<Eigen::Index>(ncols_);
  const Eigen::Index npi = static_cast<Eigen::Index>(np_);
  Eigen::MatrixXd cov(npi, npi);
  for (Eigen::Index p = 0; p < npi; ++p) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
    e[p] = 1.0;
    const Eigen::VectorXd x = ldlt.solve(e);
    cov.col(p) = x.head(npi);
  }
  // Variance factor of the weighted residuals (never scales the covariance down).
  double chi2 = 0.0;
  size_t used = 0;
  std::vector<double> abs_res;
  double sum_sq = 0.0;
  for (const Obs& o : obs_) {
    abs_res.push_back(std::fabs(o.resid));
    if (o.weight <= 0.0) continue;
    ++used;
    chi2 += o.weight * o.resid * o.resid / (scale_[o.pair] * scale_[o.pair]);
    sum_sq += o.resid * o.resid;
  }
  const double dof = static_cast<double>(used) - static_cast<double>(ncols_);
  res_.variance_factor = dof > 0.0 ? chi2 / dof : 1.0;
  cov *= std::max(1.0, res_.variance_factor);
  res_.ranges_used = used;
  res_.resid_rms_m = used > 0 ? std::sqrt(sum_sq / static_cast<double>(used)) : 0.0;
  if (!abs_res.empty()) {
    const size_t k = std::min(abs_res.size() - 1, static_cast<size_t>(0.95 * static_cast<double>(abs_res.size())));
    std::nth_element(abs_res.begin(), abs_res.begin() + static_cast<std::ptrdiff_t>(k), abs_res.end());
    res_.resid_p95_m = abs_res[k];
  }

  // Per pair: counts, residual RMS, the lag-1 autocorrelation of the used
  // residuals in time order (consecutive ranges of the pair within 1 s) and
  // their batch means over 5 s blocks. The variance of the pair's offset is
  // inflated by the larger of the AR(1) factor (1 + rho) / (1 - rho) and the
  // batch-means factor (variance of the mean from the block means over that
  // of independent residuals): errors that persist for seconds (reference
  // errors, multipath) average out far slower than white noise.
  std::vector<double> num(np_, 0.0);
  std::vector<double> slow_m2(np_, 0.0);   // lag-1 products of full-weight residuals [m^2]
  std::vector<size_t> nlag(np_, 0);
  std::vector<double> mean_fw_m(np_, 0.0);  // mean of the full-weight residuals [m]
  std::vector<size_t> cnt_fw(np_, 0);
  std::vector<double> den(np_, 0.0);
  std::vector<double> mean(np_, 0.0);
  std::vector<size_t> cnt(np_, 0);
  for (const Obs& o : obs_) {
    if (o.weight > 0.0) {
      mean[o.pair] += o.resid;
      ++cnt[o.pair];
    }
    if (o.weight >= 1.0) {
      mean_fw_m[o.pair] += o.resid;
      ++cnt_fw[o.pair];
    }
  }
  for (size_t p = 0; p < np_; ++p) {
    mean[p] = cnt[p] > 0 ? mean[p] / static_cast<double>(cnt[p]) : 0.0;
    mean_fw_m[p] = cnt_fw[p] > 0 ? mean_fw_m[p] / static_cast<double>(cnt_fw[p]) : 0.0;
  }
  std::vector<const Obs*> last(np_, nullptr);
  // Blocks keyed by (pair, recording, block index): sum and count of residuals.
  std::vector<std::vector<std::pair<uint64_t, std::pair<double, size_t>>>> blocks(np_);
  res_.pairs.assign(np_, PairResult{});
  for (const Obs& o : obs_) {
    PairResult& pr = res_.pairs[o.pair];
    ++pr.ranges;
    if (o.weight <= 0.0) {
      ++pr.rejected;
      continue;
    }
    ++pr.used;
    if (o.weight < 1.0) ++pr.downweighted;
    pr.resid_rms_m += o.resid * o.resid;
    const double e = o.resid - mean[o.pair];
    den[o.pair] += e * e;
    const Obs* l = last[o.pair];
    if (l != nullptr && l->rec == o.rec && o.t_s - l->t_s < 1.0) {
      num[o.pair] += e * (l->resid - mean[o.pair]);
      // The systematic error: full-weight neighbours only, about their own
      // mean. A down-weighted residual is an NLOS episode or an outlier (gated
      // by the filter, not part of what a LOS range carries).
      if (o.weight >= 1.0 && l->weight >= 1.0) {
        slow_m2[o.pair] += (o.resid - mean_fw_m[o.pair]) * (l->resid - mean_fw_m[o.pair]);
        ++nlag[o.pair];
      }
    }
    last[o.pair] = &o;
    const uint64_t key = (static_cast<uint64_t>(o.rec) << 32U) | static_cast<uint64_t>(std::floor(o.t_s / kBlockS));
    auto& bl = blocks[o.pair];
    if (bl.empty() || bl.back().first != key) bl.push_back({key, {0.0, 0}});
    bl.back().second.first += e;
    ++bl.back().second.second;
  }
  std::vector<double> infl(np_, 1.0);
  for (size_t p = 0; p < np_; ++p) {
    PairResult& pr = res_.pairs[p];
    const size_t a = p / site_.num_tags;
    const size_t t = p % site_.num_tags;
    pr.anchor_id = site_.anchors[a].id;
    pr.tag_id = site_.tags[t].id;
    pr.offset_m = offset_[p];
    pr.scale_m = scale_[p];
    pr.resid_rms_m = pr.used > 0 ? std::sqrt(pr.resid_rms_m / static_cast<double>(pr.used)) : 0.0;
    pr.rho = den[p] > 0.0 ? std::max(0.0, std::min(kMaxRho, num[p] / den[p])) : 0.0;
    // White noise does not correlate from one range to the next; what does is
    // the error that changes slowly with the geometry: its variance is the
    // lag-1 autocovariance (full-weight ranges of the pair within 1 s of each
    // other; docs/commissioning.md "Systematic sigma").
    pr.slow_sigma_m = nlag[p] > 0 ? std::sqrt(std::max(0.0, slow_m2[p] / static_cast<double>(nlag[p]))) : 0.0;
    double factor = (1.0 + pr.rho) / (1.0 - pr.rho);
    if (blocks[p].size() >= kMinBlocks && den[p] > 0.0 && pr.used > 0) {
      // var(mean) from the blocks, sum_b (n_b m_b)^2 / n^2 (m_b: block mean of
      // the demeaned residuals), over that of independent residuals, sum e^2 / n^2.
      double vb = 0.0;
      for (const auto& b : blocks[p]) vb += b.second.first * b.second.first;
      pr.batch_factor = vb / den[p];
      factor = std::max(factor, pr.batch_factor);
    }
    pr.inflation = std::sqrt(factor);
    infl[p] = pr.inflation;
    pr.ls_sigma_m = std::sqrt(std::max(0.0, cov(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p))));
    res_.ranges_downweighted += pr.downweighted;
    res_.ranges_rejected += pr.rejected;
  }
  for (Eigen::Index a = 0; a < npi; ++a) {
    for (Eigen::Index b = 0; b < npi; ++b) cov(a, b) *= infl[static_cast<size_t>(a)] * infl[static_cast<size_t>(b)];
  }
  res_.observable = true;
  for (size_t p = 0; p < np_; ++p) {
    PairResult& pr = res_.pairs[p];
    pr.sigma_m = std::sqrt(std::max(0.0, cov(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p))));
    pr.observable = pr.used >= kMinRangesPerPair && pr.sigma_m <= opt_.max_sigma_m;
    res_.observable = res_.observable && pr.observable;
  }
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(npi) / static_cast<double>(np_);
  res_.common_sigma_m = std::sqrt(std::max(0.0, ones.dot(cov * ones)));
  // RMS over the pairs that have consecutive full-weight ranges
  // (docs/commissioning.md "Systematic sigma"); NaN: none has, not measured.
  double slow_sq_m2 = 0.0;
  size_t slow_pairs = 0;
  for (size_t p = 0; p < np_; ++p) {
    if (nlag[p] == 0) continue;
    slow_sq_m2 += res_.pairs[p].slow_sigma_m * res_.pairs[p].slow_sigma_m;
    ++slow_pairs;
  }
  res_.systematic_sigma_m = slow_pairs > 0 ? std::sqrt(slow_sq_m2 / static_cast<double>(slow_pairs))
                                           : std::numeric_limits<double>::quiet_NaN();
  describe_weak(cov);
  for (size_t r = 0; r < zcol_.size(); ++r) {
    if (zcol_[r] >= 0) res_.body_z_m.push_back(zg_[r]);
  }
}

void Solver::describe_weak(const Eigen::MatrixXd& cov) {
  for (size_t p = 0; p < np_; ++p) {
    const PairResult& pr = res_.pairs[p];
    if (pr.used < kMinRangesPerPair) {
      res_.weak.push_back({"anchor " + std::to_string(pr.anchor_id) + " / tag " + std::to_string(pr.tag_id) + ": " +
                               std::to_string(pr.used) + " usable ranges (need " + std::to_string(kMinRangesPerPair) +
                               "); drive where this pair ranges",
                           pr.sigma_m});
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  if (eig.info() != Eigen::Success) return;
  const Eigen::Index n = cov.rows();
  const double inv_sqrt_n = 1.0 / std::sqrt(static_cast<double>(n));
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    const double sig = std::sqrt(std::max(0.0, eig.eigenvalues()[i]));
    if (sig <= opt_.max_sigma_m) break;
    const Eigen::VectorXd v = eig.eigenvectors().col(i);
    std::string what;
    if (std::fabs(v.sum() * inv_sqrt_n) > 0.9) {
      what = "the common offset of all pairs (their mean): add a reference (truth or static points), more "
             "anchors around the path, or fix it with --common-offset";
    } else {
      // The anchor or tag carrying most of the direction.
      double best = 0.0;
      std::string who;
      for (size_t a = 0; a < site_.num_anchors; ++a) {
        double e = 0.0;
        for (size_t t = 0; t < site_.num_tags; ++t) e += v[static_cast<Eigen::Index>(a * site_.num_tags + t)] *
                                                        v[static_cast<Eigen::Index>(a * site_.num_tags + t)];
        if (e > best) {
          best = e;
          who = "the pairs of anchor " + std::to_string(site_.anchors[a].id);
        }
      }
      for (size_t t = 0; t < site_.num_tags && site_.num_tags > 1; ++t) {
        double e = 0.0;
        for (size_t a = 0; a < site_.num_anchors; ++a) e += v[static_cast<Eigen::Index>(a * site_.num_tags + t)] *
                                                            v[static_cast<Eigen::Index>(a * site_.num_tags + t)];
        if (e > best) {
          best = e;
          who = "the pairs of tag " + std::to_string(site_.tags[t].id);
        }
      }
      char buf[64];
      std::snprintf(buf, sizeof buf, " (%.0f %% of the combination)", 100.0 * best);
      what = "a combination of offsets, mostly " + who + buf;
    }
    res_.weak.push_back({what, sig});
  }
}

// offset_p = d_anchor + d_tag, weighted by 1/sigma_p^2, with sum_t d_tag = 0.
void Solver::decompose() {
  Decomposition& dc = res_.decomposition;
  const size_t na = site_.num_anchors;
  const size_t nt = site_.num_tags;
  const size_t nu = na + nt;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nu), static_cast<Eigen::Index>(nu));
  Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nu));
  size_t n_obs = 0;
  for (size_t p = 0; p < np_; ++p) {
    const PairResult& pr = res_.pairs[p];
    if (!(pr.sigma_m > 0.0) || pr.used == 0) continue;
    ++n_obs;
    const double w = 1.0 / (pr.sigma_m * pr.sigma_m);
    const Eigen::Index ia = static_cast<Eigen::Index>(p / nt);
    const Eigen::Index it = static_cast<Eigen::Index>(na + p % nt);
    h(ia, ia) += w;
    h(it, it) += w;
    h(ia, it) += w;
    h(it, ia) += w;
    g[ia] += w * pr.offset_m;
    g[it] += w * pr.offset_m;
  }
  // Gauge sum_t d_t = 0 as a stiff constraint row.
  double wmax = 0.0;
  for (Eigen::Index i = 0; i < h.rows(); ++i) wmax = std::max(wmax, h(i, i));
  const double qc = 1e6 * std::max(1.0, wmax);
  for (size_t a = na; a < nu; ++a) {
    for (size_t b = na; b < nu; ++b) h(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) += qc;
  }
  for (Eigen::Index i = 0; i < h.rows(); ++i) h(i, i) += 1e-12 * std::max(1.0, wmax);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(h);
  const Eigen::VectorXd d = ldlt.solve(g);
  const Eigen::MatrixXd cov = ldlt.solve(Eigen::MatrixXd::Identity(h.rows(), h.cols()));
  dc.anchor_m.assign(na, 0.0);
  dc.anchor_sigma_m.assign(na, 0.0);
  dc.tag_m.assign(nt, 0.0);
  dc.tag_sigma_m.assign(nt, 0.0);
  for (size_t a = 0; a < na; ++a) {
    dc.anchor_m[a] = d[static_cast<Eigen::Index>(a)];
    dc.anchor_sigma_m[a] = std::sqrt(std::max(0.0, cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(a))));
  }
  for (size_t t = 0; t < nt; ++t) {
    dc.tag_m[t] = d[static_cast<Eigen::Index>(na + t)];
    dc.tag_sigma_m[t] =
        std::sqrt(std::max(0.0, cov(static_cast<Eigen::Index>(na + t), static_cast<Eigen::Index>(na + t))));
  }
  dc.resid_m.assign(np_, 0.0);
  double sq = 0.0;
  double chi2 = 0.0;
  dc.resid_max_m = 0.0;
  for (size_t p = 0; p < np_; ++p) {
    const PairResult& pr = res_.pairs[p];
    const double r = pr.offset_m - dc.anchor_m[p / nt] - dc.tag_m[p % nt];
    dc.resid_m[p] = r;
    if (!(pr.sigma_m > 0.0) || pr.used == 0) continue;
    sq += r * r;
    chi2 += r * r / (pr.sigma_m * pr.sigma_m);
    dc.resid_max_m = std::max(dc.resid_max_m, std::fabs(r));
  }
  dc.resid_rms_m = n_obs > 0 ? std::sqrt(sq / static_cast<double>(n_obs)) : 0.0;
  const size_t params = na + nt - 1;
  dc.testable = na >= 2 && nt >= 2 && n_obs > params;
  dc.dof = dc.testable ? n_obs - params : 0;
  dc.chi2_per_dof = dc.dof > 0 ? chi2 / static_cast<double>(dc.dof) : 0.0;
}

Status Solver::run(std::string* error) {
  np_ = site_.num_anchors * site_.num_tags;
  offset_.assign(np_, 0.0);
  scale_.assign(np_, 1.0);
  zg_.assign(recs_.size(), opt_.body_z_m);
  res_.site = site_;
  for (const dataset::Recording& rec : recs_) t0_us_.push_back(rec.uwb.empty() ? 0 : rec.uwb.front().range.t_us);

  Method m = opt_.method;
  if (m == Method::kAuto) {
    bool truth = true;
    for (const auto& rec : recs_) truth = truth && rec.truth.size() >= 2;
    bool stat = opt_.static_points.size() == recs_.size();
    for (const auto& sp : opt_.static_points) stat = stat && !sp.empty();
    m = truth ? Method::kTruth : (stat ? Method::kStatic : Method::kSelf);
  }
  res_.method = m;
  Status s = Status::kOk;
  if (m == Method::kTruth) s = build_truth(error);
  if (m == Method::kStatic) s = build_static(error);
  if (m == Method::kSelf) s = build_self(error);
  if (!ok(s)) return s;
  if (obs_.empty()) {
    if (error) *error = "no range with a reference position (method " + std::string(method_name(m)) + ")";
    return Status::kInvalidArgument;
  }
  assign_columns();
  res_.knots = knots_.size();

  // Initial trajectory: every knot from the ranges within one knot spacing
  // (self), or the heading of static points with unknown yaw.
  if (!knots_.empty()) {
    std::vector<size_t> idx;
    std::vector<std::vector<size_t>> by_knot(knots_.size());
    for (size_t i = 0; i < obs_.size(); ++i) {
      const Obs& o = obs_[i];
      if (o.k0 < 0) continue;
      const size_t k = static_cast<size_t>(o.k0);
      if (m == Method::kSelf) {
        by_knot[o.w1 < 0.5 ? k : k + 1].push_back(i);
      } else {
        by_knot[k].push_back(i);
      }
    }
    for (size_t k = 0; k < knots_.size(); ++k) {
      if (knots_[k].initialised) continue;
      idx.clear();
      for (size_t j = (k > 0 ? k - 1 : 0); j <= std::min(k + 1, knots_.size() - 1); ++j) {
        if (knots_[j].seg == knots_[k].seg || m != Method::kSelf) {
          if (m != Method::kSelf && j != k) continue;
          idx.insert(idx.end(), by_knot[j].begin(), by_knot[j].end());
        }
      }
      size_t n_free = 0;
      for (bool f : knots_[k].free) n_free += f ? 1U : 0U;
      if (idx.size() < n_free + 1) continue;
      const bool have_start = m == Method::kSelf && k > 0 && knots_[k - 1].seg == knots_[k].seg && knots_[k - 1].initialised;
      if (have_start) {
        for (int j = 0; j < 4; ++j) {
          if (knots_[k].free[j]) knots_[k].s[j] = knots_[k - 1].s[j];
        }
      }
      init_knot_pose(k, idx, have_start);
    }
    // Knots without enough ranges take the nearest initialised knot's state;
    // yaw is unwrapped along each segment.
    for (size_t k = 0; k < knots_.size(); ++k) {
      if (knots_[k].initialised) continue;
      for (size_t dist = 1; dist < knots_.size(); ++dist) {
        const size_t cand[2] = {k >= dist ? k - dist : knots_.size(), k + dist};
        bool done = false;
        for (size_t c : cand) {
          if (c < knots_.size() && knots_[c].initialised && knots_[c].rec == knots_[k].rec) {
            for (int j = 0; j < 4; ++j) {
              if (knots_[k].free[j]) knots_[k].s[j] = knots_[c].s[j];
            }
            done = true;
            break;
          }
        }
        if (done) break;
      }
    }
    for (size_t k = 1; k < knots_.size(); ++k) {
      if (knots_[k].seg == knots_[k - 1].seg && knots_[k].free[3]) {
        knots_[k].s[3] = knots_[k - 1].s[3] + wrap_pi(knots_[k].s[3] - knots_[k - 1].s[3]);
      }
    }
  }

  // Levenberg-Marquardt on the IRLS objective: each outer iteration fixes the
  // robust weights and scales, then takes a damped Gauss-Newton step that
  // must lower the objective (the damping grows until it does).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  Eigen::SparseMatrix<double> h;
  Eigen::VectorXd rhs;
  bool converged = false;
  double lambda = 1e-4;
  for (int it = 0;; ++it) {
    evaluate();
    build_normal(h, rhs);
    res_.iterations = it;
    if (converged || it >= opt_.max_iterations) break;
    const double f0 = cost();
    const std::vector<double> offset0 = offset_;
    const std::vector<double> zg0 = zg_;
    const std::vector<Knot> knots0 = knots_;
    Eigen::SparseMatrix<double> damped = h;
    bool accepted = false;
    double max_off = 0.0;
    double max_state = 0.0;
    for (int attempt = 0; attempt < 20 && !accepted; ++attempt) {
      damped = h;
      for (Eigen::Index c = 0; c < damped.rows(); ++c) damped.coeffRef(c, c) += lambda * (h.coeff(c, c) + 1e-9);
      ldlt.compute(damped);
      if (ldlt.info() == Eigen::Success) {
        const Eigen::VectorXd dx = ldlt.solve(rhs);
        apply(dx, max_off, max_state);
        if (std::isfinite(cost()) && cost() <= f0) {
          accepted = true;
          lambda = std::max(1e-9, lambda * 0.1);
          break;
        }
        offset_ = offset0;
        zg_ = zg0;
        knots_ = knots0;
      }
      lambda *= 10.0;
    }
    converged = !accepted || (it >= 2 && max_off < 1e-5 && max_state < 1e-4);
  }
  // Covariance from the undamped normal matrix at the solution (a tiny ridge
  // only if it is numerically singular: those directions come out with huge sigmas).
  ldlt.compute(h);
  if (ldlt.info() != Eigen::Success) {
    Eigen::SparseMatrix<double> ridge = h;
    double dmax = 0.0;
    for (Eigen::Index c = 0; c < h.rows(); ++c) dmax = std::max(dmax, h.coeff(c, c));
    for (Eigen::Index c = 0; c < ridge.rows(); ++c) ridge.coeffRef(c, c) += 1e-12 * dmax;
    ldlt.compute(ridge);
    if (ldlt.info() != Eigen::Success) {
      if (error) *error = "normal equations singular (no usable geometry)";
      return Status::kInvalidArgument;
    }
    res_.notes.push_back("normal matrix numerically singular; regularised for the covariance");
  }
  res_.converged = converged;
  finish(ldlt);
  decompose();
  if (!converged) res_.notes.push_back("not converged after " + std::to_string(opt_.max_iterations) + " iterations");
  return Status::kOk;
}

}  // namespace

const char* method_name(Method m) {
  switch (m) {
    case Method::kAuto: return "auto";
    case Method::kTruth: return "truth";
    case Method::kStatic: return "static";
    case Method::kSelf: return "self";
  }
  return "unknown";
}

Status calibrate(const std::vector<dataset::Recording>& recs, const Options& options, Result& result,
                 std::string* error) {
  result = Result{};
  if (recs.empty()) {
    if (error) *error = "no recording";
    return Status::kInvalidArgument;
  }
  const uint32_t crc = dataset::site_crc32(recs.front().site);
  for (const auto& rec : recs) {
    if (dataset::site_crc32(rec.site) != crc) {
      if (error) *error = rec.name() + ": anchors/tags differ from " + recs.front().name() + " (one site per calibration)";
      return Status::kInvalidArgument;
    }
  }
  if (options.knot_s < 0.0 || !(options.max_sigma_m > 0.0) || !(options.prior_sigma_m > 0.0)) {
    if (error) *error = "knot spacing must be >= 0 (0: auto), max sigma and prior sigma > 0";
    return Status::kInvalidArgument;
  }
  Solver solver(recs, options, result);
  return solver.run(error);
}

dataset::CalibrationFile to_calibration_file(const Result& result, const std::vector<std::string>& sources) {
  dataset::CalibrationFile f;
  double site_sigma = 0.0;
  for (const PairResult& p : result.pairs) {
    dataset::CalibrationPair cp;
    cp.anchor_id = p.anchor_id;
    cp.tag_id = p.tag_id;
    cp.offset_m = static_cast<float>(p.offset_m);
    cp.sigma_m = static_cast<float>(p.sigma_m);
    site_sigma = std::max(site_sigma, p.sigma_m);
    f.pairs.push_back(cp);
  }
  f.site_sigma_m = static_cast<float>(site_sigma);
  // Only a reference trajectory shows the whole systematic error: a
  // self-calibration's trajectory bends to part of the survey error (measured:
  // anchors surveyed to 5 cm, 7 mm seen, the filter's error 39 mm at a claimed
  // 30 mm), and a few static points see few lines of sight. Without it the
  // filter keeps uwb.survey_sigma.
  // A figure beyond the file's 1 m bound is no survey error: left out too.
  if (result.method == Method::kTruth && std::isfinite(result.systematic_sigma_m) &&
      result.systematic_sigma_m <= 1.0) {
    f.systematic_sigma_m = static_cast<float>(result.systematic_sigma_m);
  }
  f.has_site_crc = true;
  f.site_crc32 = dataset::site_crc32(result.site);
  f.info.push_back(std::string("method = ") + method_name(result.method));
  std::string src;
  for (const auto& s : sources) src += (src.empty() ? "" : " ") + s;
  f.info.push_back("recordings = " + src);
  char buf[200];
  std::snprintf(buf, sizeof buf, "ranges_used = %zu", result.ranges_used);
  f.info.push_back(buf);
  std::snprintf(buf, sizeof buf, "residual_rms_m = %.4f", result.resid_rms_m);
  f.info.push_back(buf);
  std::snprintf(buf, sizeof buf, "common_sigma_m = %.4f", result.common_sigma_m);
  f.info.push_back(buf);
  return f;
}

void print_report(std::FILE* out, const Result& r, const Options& opt) {
  const SiteConfig& s = r.site;
  char knots[96] = "";
  if (r.knots > 0 && r.knot_s > 0.0) {
    std::snprintf(knots, sizeof knots, ", %zu trajectory knots every %.3f s", r.knots, r.knot_s);
  } else if (r.knots > 0) {
    std::snprintf(knots, sizeof knots, ", %zu static points", r.knots);
  }
  std::fprintf(out, "calibrate: method %s, %zu pairs (%zu anchors x %zu tags)%s\n", method_name(r.method),
               r.pairs.size(), s.num_anchors, s.num_tags, knots);
  std::fprintf(out,
               "ranges: %zu in the recordings, %zu with a reference, used %zu (down-weighted %zu beyond %.1f sigma, "
               "rejected %zu beyond %.1f sigma), no reference %zu, unknown anchor/tag %zu\n",
               r.ranges_total, r.ranges_total - r.ranges_no_reference - r.ranges_unknown, r.ranges_used,
               r.ranges_downweighted, opt.huber_k, r.ranges_rejected, opt.reject_k, r.ranges_no_reference,
               r.ranges_unknown);
  std::fprintf(out, "residuals: rms %.4f m (used), |residual| p95 %.4f m (all), variance factor %.2f, %d iterations%s\n",
               r.resid_rms_m, r.resid_p95_m, r.variance_factor, r.iterations, r.converged ? "" : " (NOT converged)");
  for (size_t i = 0; i < r.body_z_m.size(); ++i) {
    std::fprintf(out, "body-origin height of recording %zu: %.3f m (estimated)\n", i + 1, r.body_z_m[i]);
  }
  for (const auto& n : r.notes) std::fprintf(out, "note: %s\n", n.c_str());
  std::fprintf(out, "per pair (offset = measured minus true range; sigma = LS sigma x sqrt(variance factor) x "
                    "inflation for correlated residuals):\n");
  std::fprintf(out, "  anchor tag  offset_m  sigma_m  ls_sigma_m   rho  batch  infl  ranges    used  downw  rej  scale_m  rms_m  slow_m\n");
  for (const PairResult& p : r.pairs) {
    std::fprintf(out, "  %6u %3u %9.4f %8.4f %11.5f %5.2f %6.1f %5.2f %7zu %7zu %6zu %4zu %8.4f %6.4f %7.4f%s\n",
                 static_cast<unsigned>(p.anchor_id), static_cast<unsigned>(p.tag_id), p.offset_m, p.sigma_m,
                 p.ls_sigma_m, p.rho, p.batch_factor, p.inflation, p.ranges, p.used, p.downweighted, p.rejected,
                 p.scale_m, p.resid_rms_m, p.slow_sigma_m, p.observable ? "" : "  NOT OBSERVABLE");
  }
  const Decomposition& d = r.decomposition;
  if (!d.anchor_m.empty()) {
    std::fprintf(out, "decomposition offset ~= d_anchor + d_tag (sum of d_tag = 0):\n");
    for (size_t a = 0; a < d.anchor_m.size(); ++a) {
      std::fprintf(out, "  anchor %u: d = %.4f +- %.4f m\n", static_cast<unsigned>(s.anchors[a].id), d.anchor_m[a],
                   d.anchor_sigma_m[a]);
    }
    for (size_t t = 0; t < d.tag_m.size(); ++t) {
      std::fprintf(out, "  tag %u: d = %.4f +- %.4f m\n", static_cast<unsigned>(s.tags[t].id), d.tag_m[t],
                   d.tag_sigma_m[t]);
    }
    if (d.testable) {
      std::fprintf(out, "  fit residual: rms %.4f m, max %.4f m, chi2/dof %.2f (dof %zu)%s\n", d.resid_rms_m,
                   d.resid_max_m, d.chi2_per_dof, d.dof,
                   d.chi2_per_dof > 4.0 ? ": the pairs do not split into anchor + tag delays, keep per-pair offsets" : "");
    } else {
      std::fprintf(out, "  fit not testable (needs >= 2 anchors and >= 2 tags): the per-anchor terms are the pair offsets\n");
    }
  }
  std::fprintf(out, "common offset (mean of all pairs): 1-sigma %.4f m\n", r.common_sigma_m);
  double slow_max_m = 0.0;
  for (const PairResult& p : r.pairs) slow_max_m = std::max(slow_max_m, p.slow_sigma_m);
  if (!std::isfinite(r.systematic_sigma_m)) {
    std::fprintf(out, "systematic range error left after the offsets: not measured (no pair has consecutive "
                      "full-weight ranges); the filter keeps uwb.survey_sigma\n");
  } else {
    std::fprintf(out,
                 "systematic range error left after the offsets (slowly varying residual): 1-sigma %.4f m (RMS over "
                 "the pairs, max %.4f m); %s\n",
                 r.systematic_sigma_m, slow_max_m,
                 r.method == Method::kTruth
                     ? "written to the file: the filter carries it in place of uwb.survey_sigma"
                     : "not written (only a reference trajectory shows it whole): the filter keeps uwb.survey_sigma, "
                       "set it from the survey");
  }
  if (r.observable) {
    std::fprintf(out, "observability: every offset determined to <= %.4f m (1-sigma)\n", opt.max_sigma_m);
  } else {
    std::fprintf(out, "observability: NOT every offset is determined to %.4f m (1-sigma):\n", opt.max_sigma_m);
    for (const WeakDirection& w : r.weak) std::fprintf(out, "  sigma %.3f m: %s\n", w.sigma_m, w.what.c_str());
  }
}

}  // namespace uwbnav::calib
