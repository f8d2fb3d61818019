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

constexpr uint64_t kPeriodUs = 10000;  // the firmware's 10 ms epoch

void rotate(const double q[4], const double v[3], double out[3]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  for (int i = 0; i < 3; ++i) out[i] = r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2];
}

}  // namespace

dataset::TruthRow tag_truth_row(const SiteConfig& site, const dataset::TruthRow& body) {
  dataset::TruthRow t = body;
  if (site.num_tags == 0) return t;
  const Vec3f l = site.tags[0].lever_body_m;
  const double lever[3] = {l.x, l.y, l.z};
  double d[3] = {0.0, 0.0, lever[2]};
  if (t.has_attitude) rotate(t.q_nav_body, lever, d);
  for (int k = 0; k < 3; ++k) t.pos_nav_m[k] += d[k];
  return t;
}

std::vector<dataset::TruthRow> tag_truth(const dataset::Recording& rec) {
  std::vector<dataset::TruthRow> out;
  out.reserve(rec.truth.size());
  for (const auto& t : rec.truth) out.push_back(tag_truth_row(rec.site, t));
  return out;
}

LsBaseline::LsBaseline(const SiteConfig& site, LsMethod method, FixFn on_fix, uint64_t window_us)
    : site_(site), method_(method), on_fix_(std::move(on_fix)), window_us_(window_us) {
  tag_ = site.num_tags > 0 ? site.tags[0].id : 0;
  two_d_ = anchors_planar(site);
  tag_z_m_ = site.num_tags > 0 ? site.tags[0].lever_body_m.z : 0.0F;
}

void LsBaseline::add(const UwbRange& r) {
  if (site_.num_anchors == 0) return;
  if (!started_) {
    started_ = true;
    next_epoch_us_ = (r.t_us / kPeriodUs + 1) * kPeriodUs;
  }
  while (next_epoch_us_ < r.t_us) solve(next_epoch_us_);  // epochs before this range
  t_last_range_us_ = r.t_us;
  if (r.tag_id != tag_ || !std::isfinite(r.range_m)) return;
  const int a = site_.find_anchor(r.anchor_id);
  if (a < 0) return;
  last_t_us_[a] = r.t_us;
  last_range_m_[a] = r.range_m;
  have_[a] = true;
}

void LsBaseline::advance_to(uint64_t t_us) {
  if (!started_) return;
  while (next_epoch_us_ <= t_us) solve(next_epoch_us_);
}

void LsBaseline::finish() { advance_to(t_last_range_us_ + kPeriodUs); }

void LsBaseline::solve(uint64_t t) {
  next_epoch_us_ = t + kPeriodUs;
  const float sigma = 0.1F;  // equal weights: the baseline knows no noise level
  LsRange ranges[kMaxAnchors];
  size_t n = 0;
  for (size_t a = 0; a < site_.num_anchors; ++a) {
    if (!have_[a] || t - last_t_us_[a] > window_us_) continue;
    ranges[n].anchor_pos_nav_m = site_.anchors[a].pos_nav_m;
    ranges[n].range_m = last_range_m_[a];
    ranges[n].sigma_m = sigma;
    ++n;
  }
  LsOptions opt;
  opt.two_d = two_d_;
  opt.known_z_m = tag_z_m_;
  if (method_ == LsMethod::kLinear) {
    opt.max_iterations = 0;
  } else if (have_prev_) {
    opt.has_initial_guess = true;
    opt.initial_guess_nav_m = prev_nav_m_;
  }
  LsFix fix;
  if (!ok(ls_taylor_solve(ranges, n, opt, fix))) return;
  prev_nav_m_ = fix.pos_nav_m;
  have_prev_ = true;
  dataset::EstimateRow row;
  row.t_us = t;
  row.pos_nav_m[0] = fix.pos_nav_m.x;
  row.pos_nav_m[1] = fix.pos_nav_m.y;
  row.pos_nav_m[2] = fix.pos_nav_m.z;
  for (int k = 0; k < 3; ++k) row.pos_sigma_m[k] = std::sqrt(std::max(0.0F, fix.cov_nav_m2[k][k]));
  row.status = 1;
  on_fix_(row);
}

std::vector<dataset::EstimateRow> ls_baseline(const dataset::Recording& rec, LsMethod method, uint64_t window_us) {
  std::vector<dataset::EstimateRow> out;
  LsBaseline ls(rec.site, method, [&out](const dataset::EstimateRow& row) { out.push_back(row); }, window_us);
  for (const auto& u : rec.uwb) ls.add(u.range);
  ls.finish();
  return out;
}

}  // namespace uwbnav::eval
