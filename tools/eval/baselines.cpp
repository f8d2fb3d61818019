// LS-UWB and LS-Taylor baselines (see baselines.hpp).
#include "tools/eval/baselines.hpp"

#include <algorithm>
#include <cmath>

#include "estimator/ls_taylor.hpp"

namespace uwbnav::eval {
namespace {

bool anchors_planar(const SiteConfig& site) {
  float zmin = 1e9F;
  float zmax = -1e9F;
  for (size_t i = 0; i < site.num_anchors; ++i) {
    zmin = std::min(zmin, site.anchors[i].pos_nav_m.z);
    zmax = std::max(zmax, site.anchors[i].pos_nav_m.z);
  }
  return zmax - zmin < 0.5F;
}

void rotate(const double q[4], const double v[3], double out[3]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  for (int i = 0; i < 3; ++i) out[i] = r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2];
}

}  // namespace

std::vector<dataset::TruthRow> tag_truth(const dataset::Recording& rec) {
  std::vector<dataset::TruthRow> out = rec.truth;
  if (rec.site.num_tags == 0) return out;
  const Vec3f l = rec.site.tags[0].lever_body_m;
  const double lever[3] = {l.x, l.y, l.z};
  for (auto& t : out) {
    double d[3] = {0.0, 0.0, lever[2]};
    if (t.has_attitude) rotate(t.q_nav_body, lever, d);
    for (int k = 0; k < 3; ++k) t.pos_nav_m[k] += d[k];
  }
  return out;
}

std::vector<dataset::EstimateRow> ls_baseline(const dataset::Recording& rec, LsMethod method, uint64_t window_us) {
  std::vector<dataset::EstimateRow> out;
  if (rec.uwb.empty() || rec.site.num_anchors == 0) return out;
  const uint8_t tag = rec.site.num_tags > 0 ? rec.site.tags[0].id : 0;
  const bool two_d = anchors_planar(rec.site);
  const float tag_z = rec.site.num_tags > 0 ? rec.site.tags[0].lever_body_m.z : 0.0F;
  const float sigma = 0.1F;  // equal weights: the baseline knows no noise level

  uint64_t last_t[kMaxAnchors] = {};
  float last_r[kMaxAnchors] = {};
  bool have[kMaxAnchors] = {};
  size_t next = 0;
  const uint64_t period = 10000;
  const uint64_t t_first = rec.uwb.front().range.t_us;
  const uint64_t t_last = rec.uwb.back().range.t_us;
  bool have_prev = false;
  Vec3f prev{};
  for (uint64_t t = (t_first / period + 1) * period; t <= t_last + period; t += period) {
    while (next < rec.uwb.size() && rec.uwb[next].range.t_us <= t) {
      const UwbRange& r = rec.uwb[next++].range;
      if (r.tag_id != tag || !std::isfinite(r.range_m)) continue;
      const int a = rec.site.find_anchor(r.anchor_id);
      if (a < 0) continue;
      last_t[a] = r.t_us;
      last_r[a] = r.range_m;
      have[a] = true;
    }
    LsRange ranges[kMaxAnchors];
    size_t n = 0;
    for (size_t a = 0; a < rec.site.num_anchors; ++a) {
      if (!have[a] || t - last_t[a] > window_us) continue;
      ranges[n].anchor_pos_nav_m = rec.site.anchors[a].pos_nav_m;
      ranges[n].range_m = last_r[a];
      ranges[n].sigma_m = sigma;
      ++n;
    }
    LsOptions opt;
    opt.two_d = two_d;
    opt.known_z_m = tag_z;
    if (method == LsMethod::kLinear) {
      opt.max_iterations = 0;
    } else if (have_prev) {
      opt.has_initial_guess = true;
      opt.initial_guess_nav_m = prev;
    }
    LsFix fix;
    if (!ok(ls_taylor_solve(ranges, n, opt, fix))) continue;
    prev = fix.pos_nav_m;
    have_prev = true;
    dataset::EstimateRow row;
    row.t_us = t;
    row.pos_nav_m[0] = fix.pos_nav_m.x;
    row.pos_nav_m[1] = fix.pos_nav_m.y;
    row.pos_nav_m[2] = fix.pos_nav_m.z;
    for (int k = 0; k < 3; ++k) row.pos_sigma_m[k] = std::sqrt(std::max(0.0F, fix.cov_nav_m2[k][k]));
    row.status = 1;
    out.push_back(row);
  }
  return out;
}

}  // namespace uwbnav::eval
