// Accuracy metrics against truth (see metrics.hpp).
#include "tools/eval/metrics.hpp"

#include <algorithm>
#include <cmath>

namespace uwbnav::eval {

bool truth_at(const std::vector<dataset::TruthRow>& truth, uint64_t t_us, double pos_nav_m[3], uint64_t max_gap_us) {
  if (truth.empty() || t_us < truth.front().t_us || t_us > truth.back().t_us) return false;
  auto it = std::lower_bound(truth.begin(), truth.end(), t_us,
                             [](const dataset::TruthRow& r, uint64_t t) { return r.t_us < t; });
  if (it == truth.end()) return false;
  if (it->t_us == t_us) {
    for (int k = 0; k < 3; ++k) pos_nav_m[k] = it->pos_nav_m[k];
    return true;
  }
  const auto& b = *it;
  const auto& a = *(it - 1);
  if (b.t_us - a.t_us > max_gap_us) return false;
  const double w = static_cast<double>(t_us - a.t_us) / static_cast<double>(b.t_us - a.t_us);
  for (int k = 0; k < 3; ++k) pos_nav_m[k] = a.pos_nav_m[k] + w * (b.pos_nav_m[k] - a.pos_nav_m[k]);
  return true;
}

std::vector<ErrorSample> compare_with_truth(const std::vector<dataset::EstimateRow>& est,
                                            const std::vector<dataset::TruthRow>& truth) {
  std::vector<ErrorSample> out;
  out.reserve(est.size());
  for (const auto& e : est) {
    if (e.status != 1 && e.status != 2) continue;  // valid or degraded only
    double p[3];
    if (!truth_at(truth, e.t_us, p)) continue;
    ErrorSample s;
    s.t_us = e.t_us;
    s.status = e.status;
    for (int k = 0; k < 3; ++k) {
      s.err_nav_m[k] = e.pos_nav_m[k] - p[k];
      s.sigma_nav_m[k] = e.pos_sigma_m[k];
    }
    out.push_back(s);
  }
  return out;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::nan("");
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(std::floor(q * static_cast<double>(values.size() - 1) + 0.5)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

AccuracyStats accuracy(const std::vector<ErrorSample>& errors, size_t epochs_total) {
  AccuracyStats st;
  st.epochs = errors.size();
  st.epochs_total = epochs_total;
  if (errors.empty()) {
    const double nan = std::nan("");
    st.rmse_h_m = st.max_h_m = st.std_h_m = st.mean_h_m = nan;
    st.p50_east_m = st.p70_east_m = st.p90_east_m = nan;
    st.p50_north_m = st.p70_north_m = st.p90_north_m = nan;
    st.inside_2sigma_x = st.inside_2sigma_y = nan;
    return st;
  }
  std::vector<double> h, ex, ey;
  h.reserve(errors.size());
  ex.reserve(errors.size());
  ey.reserve(errors.size());
  double sum2 = 0.0, sum = 0.0;
  size_t in_x = 0, in_y = 0, with_sigma = 0;
  for (const auto& e : errors) {
    const double hh = std::hypot(e.err_nav_m[0], e.err_nav_m[1]);
    h.push_back(hh);
    ex.push_back(std::fabs(e.err_nav_m[0]));
    ey.push_back(std::fabs(e.err_nav_m[1]));
    sum2 += hh * hh;
    sum += hh;
    st.max_h_m = std::max(st.max_h_m, hh);
    if (std::isfinite(e.sigma_nav_m[0]) && std::isfinite(e.sigma_nav_m[1])) {
      ++with_sigma;
      if (std::fabs(e.err_nav_m[0]) <= 2.0 * e.sigma_nav_m[0]) ++in_x;
      if (std::fabs(e.err_nav_m[1]) <= 2.0 * e.sigma_nav_m[1]) ++in_y;
    }
  }
  const double n = static_cast<double>(errors.size());
  st.rmse_h_m = std::sqrt(sum2 / n);
  st.mean_h_m = sum / n;
  double var = 0.0;
  for (double v : h) var += (v - st.mean_h_m) * (v - st.mean_h_m);
  st.std_h_m = std::sqrt(var / n);
  st.p50_east_m = quantile(ex, 0.5);
  st.p70_east_m = quantile(ex, 0.7);
  st.p90_east_m = quantile(ex, 0.9);
  st.p50_north_m = quantile(ey, 0.5);
  st.p70_north_m = quantile(ey, 0.7);
  st.p90_north_m = quantile(ey, 0.9);
  if (with_sigma > 0) {
    st.inside_2sigma_x = static_cast<double>(in_x) / static_cast<double>(with_sigma);
    st.inside_2sigma_y = static_cast<double>(in_y) / static_cast<double>(with_sigma);
  }
  return st;
}

void interpolate(const dataset::TruthRow& a, const dataset::TruthRow& b, uint64_t t_us, double pos_nav_m[3]) {
  const double w = static_cast<double>(t_us - a.t_us) / static_cast<double>(b.t_us - a.t_us);
  for (int k = 0; k < 3; ++k) pos_nav_m[k] = a.pos_nav_m[k] + w * (b.pos_nav_m[k] - a.pos_nav_m[k]);
}

bool TruthCursor::bracket(uint64_t t_us, const dataset::TruthRow*& before, const dataset::TruthRow*& at) {
  at = nullptr;
  before = nullptr;
  if (feed_ == nullptr) return false;
  while (feed_->peek() != nullptr && feed_->peek()->t_us < t_us) {
    have_prev_ = feed_->next(prev_);
  }
  at = feed_->peek();
  if (at == nullptr) return false;  // after the last row (or no truth)
  if (at->t_us == t_us) return true;
  if (!have_prev_ || at->t_us - prev_.t_us > max_gap_us_) return false;  // before the first row, or a gap
  before = &prev_;
  return true;
}

bool TruthCursor::position(uint64_t t_us, double pos_nav_m[3]) {
  const dataset::TruthRow* a = nullptr;
  const dataset::TruthRow* b = nullptr;
  if (!bracket(t_us, a, b)) return false;
  if (a == nullptr) {
    for (int k = 0; k < 3; ++k) pos_nav_m[k] = b->pos_nav_m[k];
  } else {
    interpolate(*a, *b, t_us, pos_nav_m);
  }
  return true;
}

void AccuracyAccumulator::add(const ErrorSample& e) {
  const double h = std::hypot(e.err_nav_m[0], e.err_nav_m[1]);
  ++n_;
  sum_h2_ += h * h;
  const double delta = h - mean_h_m_;
  mean_h_m_ += delta / static_cast<double>(n_);
  m2_h_ += delta * (h - mean_h_m_);
  max_h_m_ = std::max(max_h_m_, h);
  if (std::isfinite(e.sigma_nav_m[0]) && std::isfinite(e.sigma_nav_m[1])) {
    ++with_sigma_;
    if (std::fabs(e.err_nav_m[0]) <= 2.0 * e.sigma_nav_m[0]) ++in_x_;
    if (std::fabs(e.err_nav_m[1]) <= 2.0 * e.sigma_nav_m[1]) ++in_y_;
  }
}

AccuracyStats AccuracyAccumulator::stats(size_t epochs_total) const {
  AccuracyStats st;
  st.epochs = n_;
  st.epochs_total = epochs_total;
  const double nan = std::nan("");
  st.p50_east_m = st.p70_east_m = st.p90_east_m = nan;
  st.p50_north_m = st.p70_north_m = st.p90_north_m = nan;
  if (n_ == 0) {
    st.rmse_h_m = st.max_h_m = st.std_h_m = st.mean_h_m = nan;
    st.inside_2sigma_x = st.inside_2sigma_y = nan;
    return st;
  }
  const double n = static_cast<double>(n_);
  st.rmse_h_m = std::sqrt(sum_h2_ / n);
  st.mean_h_m = mean_h_m_;
  st.std_h_m = std::sqrt(m2_h_ / n);
  st.max_h_m = max_h_m_;
  if (with_sigma_ > 0) {
    st.inside_2sigma_x = static_cast<double>(in_x_) / static_cast<double>(with_sigma_);
    st.inside_2sigma_y = static_cast<double>(in_y_) / static_cast<double>(with_sigma_);
  }
  return st;
}

}  // namespace uwbnav::eval
