// Rest (standstill) detector over a sliding window of IMU samples: the vehicle
// is at rest when the specific-force magnitude barely varies and every gyro
// sample is small. Feeds ZUPT/ZARU, levelling and the gyro bias at start.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/ekf_state.hpp"

namespace uwbnav {

class RestDetector {
 public:
  static constexpr size_t kCapacity = 256;  // samples (> 1 s at 249 Hz)

  // window_s: span to judge; thresholds as params ekf.rest_*.
  void configure(Real window_s, Real accel_std_max_mps2, Real gyro_max_radps);
  void reset();
  void add(uint64_t t_us, const Vec3& accel_body_mps2, const Vec3& gyro_body_radps);
  // Judges the window ending at the newest sample (O(window); the Navigator
  // calls it at the constraint rate, not per sample).
  void evaluate();

  // Result of the last evaluate().
  bool at_rest() const { return at_rest_; }
  // Means over the current window (valid when window_full()).
  const Vec3& accel_mean() const { return accel_mean_; }
  const Vec3& gyro_mean() const { return gyro_mean_; }
  bool window_full() const { return full_; }
  Real window_span_s() const { return span_s_; }

 private:

  Vec3 accel_[kCapacity];
  Vec3 gyro_[kCapacity];
  // Low 32 bits of the sample times [us]: evaluate() sums the gaps between
  // neighbours, each exact modulo 2^32 because add() restarts the ring after a
  // gap of kMaxGapUs or more (half the RAM of full timestamps).
  static constexpr uint64_t kMaxGapUs = 0x80000000U;
  uint32_t t_lo_us_[kCapacity] = {};
  uint64_t newest_t_us_ = 0;
  size_t head_ = 0;   // next write index
  size_t count_ = 0;
  Real window_s_ = Real(0.5);
  Real accel_std_max_ = Real(0.08);
  Real gyro_max_ = Real(0.03);
  Vec3 accel_mean_ = Vec3::Zero();
  Vec3 gyro_mean_ = Vec3::Zero();
  Real span_s_ = Real(0);
  bool full_ = false;
  bool at_rest_ = false;
};

}  // namespace uwbnav
