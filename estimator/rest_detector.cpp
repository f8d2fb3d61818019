// Sliding-window rest detector (accelerometer magnitude spread, gyro spread about its mean).
#include "estimator/rest_detector.hpp"

#include <cmath>

namespace uwbnav {

void RestDetector::configure(Real window_s, Real accel_std_max_mps2, Real gyro_max_radps) {
  window_s_ = window_s;
  accel_std_max_ = accel_std_max_mps2;
  gyro_max_ = gyro_max_radps;
  reset();
}

void RestDetector::reset() {
  head_ = 0;
  count_ = 0;
  accel_mean_.setZero();
  gyro_mean_.setZero();
  span_s_ = Real(0);
  full_ = false;
  at_rest_ = false;
}

void RestDetector::add(uint64_t t_us, const Vec3& accel_body_mps2, const Vec3& gyro_body_radps) {
  // Samples this much older are outside any window (<= 1 s): dropping them
  // keeps every stored gap below 2^32 us.
  if (count_ > 0 && (t_us < newest_t_us_ || t_us - newest_t_us_ >= kMaxGapUs)) {
    head_ = 0;
    count_ = 0;
  }
  newest_t_us_ = t_us;
  accel_[head_] = accel_body_mps2;
  gyro_[head_] = gyro_body_radps;
  t_lo_us_[head_] = static_cast<uint32_t>(t_us);
  head_ = (head_ + 1) % kCapacity;
  if (count_ < kCapacity) ++count_;
}

void RestDetector::evaluate() {
  const size_t newest = (head_ + kCapacity - 1) % kCapacity;
  // Via uint32 (a single VCVT on an FPU; the window is at most seconds): a
  // direct float -> uint64 conversion is a soft-double libgcc call on Cortex-M.
  const uint64_t window_us = static_cast<uint32_t>(window_s_ * Real(1e6));
  Vec3 a_sum = Vec3::Zero();
  Vec3 g_sum = Vec3::Zero();
  Real n_sum = Real(0);
  size_t n = 0;
  uint64_t age_us = 0;   // newest sample time minus sample i's [us]
  uint64_t span_us = 0;  // newest minus the oldest sample in the window [us]
  for (size_t k = 0; k < count_; ++k) {
    const size_t i = (newest + kCapacity - k) % kCapacity;
    if (k > 0) age_us += static_cast<uint32_t>(t_lo_us_[(i + 1) % kCapacity] - t_lo_us_[i]);
    if (age_us > window_us) break;
    const Real an = accel_[i].norm();
    a_sum += accel_[i];
    g_sum += gyro_[i];
    n_sum += an;
    span_us = age_us;
    ++n;
  }
  span_s_ = static_cast<Real>(span_us) * Real(1e-6);
  // A window is judged once it spans 80 % of its length (IMU gaps shorten it).
  full_ = n >= 5 && span_s_ >= Real(0.8) * window_s_;
  if (n == 0 || count_ == 0) {
    at_rest_ = false;
    return;
  }
  const Real inv_n = Real(1) / static_cast<Real>(n);
  accel_mean_ = a_sum * inv_n;
  gyro_mean_ = g_sum * inv_n;
  const Real mean = n_sum * inv_n;
  Real g_max = Real(0);
  Real var = Real(0);  // second pass: no cancellation around |a| ~ 9.8
  for (size_t k = 0; k < n; ++k) {
    const size_t i = (newest + kCapacity - k) % kCapacity;
    const Real d = accel_[i].norm() - mean;
    var += d * d;
    // Spread of the gyro about its window mean: a consumer gyro's turn-on bias
    // (1-2 deg/s) must not read as rotation.
    g_max = std::fmax(g_max, (gyro_[i] - gyro_mean_).norm());
  }
  var *= inv_n;
  at_rest_ = full_ && std::sqrt(var) < accel_std_max_ && g_max < gyro_max_;
}

}  // namespace uwbnav
