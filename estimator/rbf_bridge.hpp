// UWB outage bridging after seed 004: while ranges are fused, free-running
// copies of the INS ("shadows", the seed's 单独INS, standalone INS) are started
// from the filter state and an RBF network (rbf_net.hpp) learns their position
// error against the UWB/INS solution; during an outage it predicts that error
// for a shadow started at the last fused range, giving a horizontal position
// pseudo-measurement with the network's own error variance (docs/ekf.md
// "Outage bridging"). Pure library, static memory.
#pragma once

#include <cstdint>

#include "estimator/ekf_state.hpp"
#include "estimator/rbf_net.hpp"

namespace uwbnav {

// Parameter ekf.rbf_bridge (float-coded): what the network does during an outage.
enum class RbfMode : uint8_t {
  kOff = 0,      // not run (no training, no cost beyond a branch)
  kOn = 1,       // trained, and fused as a pseudo-measurement during outages
  kCompare = 2,  // trained and predicted during outages, never fused (diagnostics record it)
};

// What the bridge did, for diagnostics and the compare mode. Monotonic counters.
struct RbfBridgeDiag {
  uint32_t train_samples = 0;    // training samples taken
  uint32_t windows = 0;          // training windows started
  uint32_t predictions = 0;      // valid predictions during outages (on or compare)
  uint32_t fused = 0;            // pseudo-measurement axes fused (on)
  float last_corr_x_m = 0.0F;    // latest predicted shadow error, nav x [m]
  float last_corr_y_m = 0.0F;    // nav y [m]
  float last_sigma_m = 0.0F;     // its 1-sigma, root mean of both axes [m]
  float last_tau_s = 0.0F;       // time since the shadow started (last fused range) [s]
};

class RbfBridge {
 public:
  // A horizontal position pseudo-measurement of the body origin.
  struct Correction {
    Real pos_x_nav_m = Real(0);
    Real pos_y_nav_m = Real(0);
    Real var_x_m2 = Real(0);
    Real var_y_m2 = Real(0);
    Real tau_s = Real(0);       // time since the shadow started [s]
  };

  // Training windows in flight at once (staggered by kWindowS / kTrainShadows).
  static constexpr int kTrainShadows = 3;
  // Longest coast learnt (and the centres' time span) [s].
  static constexpr Real kWindowS = Real(32);

  RbfBridge();

  void configure(RbfMode mode);
  RbfMode mode() const { return mode_; }
  // Forgets the network and every shadow (filter restarted from scratch).
  void reset();
  // The filter state jumped (recovery): windows in flight no longer measure drift.
  void restart_shadows();

  // One IMU interval of the inertial filter, after its prediction: the mean
  // samples as given to EkfCore::predict_imu, the filter state at t_us and the
  // time of its last fused range. Integrates the shadows and trains.
  void on_imu(uint64_t t_us, const Vec3& accel_mean_body_mps2, const Vec3& gyro_mean_body_radps, Real dt_s,
              Real gravity_mps2, const NominalState& filter, uint64_t last_fix_us);
  // A range fused by the inertial filter at t_us: the outage shadow restarts here.
  void on_fix(uint64_t t_us, const NominalState& filter);
  // The network's position of the body origin at t_us from the outage shadow;
  // false where the network is untrained or outside what it learnt.
  bool predict(uint64_t t_us, Correction& out);

  // The caller fused one axis of a prediction (counted in the diagnostics).
  void note_fused() { ++diag_.fused; }
  const RbfBridgeDiag& diag() const { return diag_; }
  const RbfNet& net() const { return net_; }

  // Network inputs of a shadow (seed 004 fig. 2 x_1..x_p; choice documented in
  // docs/ekf.md): time since its start / 10 s, speed at its start / 7.5 m/s,
  // heading change since its start / pi. Public for the tests.
  static RbfNet::Input inputs(Real tau_s, Real speed0_mps, Real dyaw_rad);

 private:
  // A free-running INS from a filter state: same mechanisation as
  // EkfCore::predict_imu with the biases of its start held.
  struct Shadow {
    Vec3 pos_nav_m = Vec3::Zero();
    Vec3 vel_nav_mps = Vec3::Zero();
    Quat q_nav_body = Quat(1, 0, 0, 0);
    Vec3 ba_body_mps2 = Vec3::Zero();
    Vec3 bg_body_radps = Vec3::Zero();
    uint64_t t0_us = 0;         // start [us]
    uint64_t next_sample_us = 0;  // next training sample [us]
    Real yaw0_rad = Real(0);    // heading at the start [rad]
    Real speed0_mps = Real(0);  // horizontal speed at the start [m/s]
    bool active = false;
  };

  static void start(Shadow& s, uint64_t t_us, const NominalState& filter);
  static void integrate(Shadow& s, const Vec3& f_body, const Vec3& w_body, Real dt_s, Real gravity_mps2);
  RbfNet::Input shadow_inputs(const Shadow& s, uint64_t t_us) const;

  RbfMode mode_ = RbfMode::kOff;
  RbfNet net_;
  Shadow train_[kTrainShadows];
  Shadow outage_;                 // started at every fused range
  uint64_t last_imu_us_ = 0;
  uint64_t last_window_start_us_ = 0;
  RbfBridgeDiag diag_;
};

}  // namespace uwbnav
