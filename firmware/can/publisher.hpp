// Publishes NavOutput and diagnostics on CAN: each message group at its own
// period on the 10 ms tick, E2E protected, never blocking and never retrying.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/params.hpp"
#include "estimator/types.hpp"
#include "firmware/app_stats.hpp"
#include "firmware/can/messages.hpp"
#include "hal/hal.hpp"

namespace uwbnav::can {

// Diagnostics the firmware hands the publisher each cycle (UWBNAV_Diag).
struct CanDiag {
  uint16_t nlos_mask = 0;      // bit i: last range of anchor index i (SiteConfig::anchors[i]) judged NLOS
  uint64_t loop_overruns = 0;  // LoopStats::overruns
  uint32_t input_rejects = 0;  // sum of rejected frames over all sources
  uint32_t resets = 0;         // filter resets since start (NavOutput::resets)

  // Records the NLOS decision of the latest range of anchor table index `anchor_index`.
  void set_anchor_nlos(int anchor_index, bool nlos);
  // Copies overruns and input rejects (imu + uwb + can_rx, gnss and neighbours where built) from the firmware counters.
  void set_from_stats(const AppStats& stats);
};

struct CanTxStats {
  uint32_t sent = 0;       // accepted by the bus driver
  uint32_t dropped = 0;    // kWouldBlock: driver queue full, frame dropped (not retried)
  uint32_t failed = 0;     // kIoError or other: bus off / interface down, frame dropped
  uint32_t saturated = 0;  // frames sent with the Saturated flag set
};

constexpr uint32_t kCanTickUs = 10000;  // base tick of the publisher [us]

class CanPublisher {
 public:
  // Reads can.tx_enable and the periods (rounded to multiples of 10 ms); with
  // UWBNAV_COOP also coop.vehicle_id and can.coop_period_ms.
  // Keeps the alive counters (a reconfiguration is not a restart).
  void configure(const Params& params);

#if UWBNAV_COOP
  // This vehicle's tag state for the next on_cycle() only (docs/can.md
  // "Cooperative positioning"): call it every cycle before on_cycle(), e.g.
  // with coop_state_from(). Its vehicle_id is replaced by coop_vehicle_id().
  void set_coop_state(const NeighbourState& s);
  // 0x8000 + coop.vehicle_id, or kNoVehicleId when coop.vehicle_id = 0 (no broadcast).
  uint16_t coop_vehicle_id() const { return coop_id_; }
#endif

  // Called once per 10 ms firmware cycle at loop time t_us [us]. Sends every
  // group whose period has elapsed, in the order NavTime, PosXY, PosZ, VelHdg,
  // Accuracy, Attitude, Diag, and (UWBNAV_COOP) the six UWBNAV_Coop* frames of
  // the state set this cycle when coop.vehicle_id > 0 and nav.status is valid or
  // degraded. A frame the bus refuses is counted and dropped; its alive counter
  // is still consumed so receivers see the loss.
  void on_cycle(uint64_t t_us, const NavOutput& nav, const CanDiag& diag, hal::CanBus& bus);

  const CanTxStats& stats() const { return stats_; }
  void reset_stats() { stats_ = CanTxStats{}; }

 private:
  struct Schedule {
    uint32_t period_us = kCanTickUs;
    uint64_t next_due_us = 0;
    bool started = false;
  };
  enum Slot : uint8_t {
    kNavTime = 0,
    kPosXY,
    kPosZ,
    kVelHdg,
    kAccuracy,
    kDiag,
    kAttitude,
#if UWBNAV_COOP
    kCoop,  // one counter for the six frames of a UWBNAV_Coop* group
#endif
    kNumSlots
  };

  static bool due(Schedule& s, uint64_t t_us);
  void send(Slot slot, hal::CanFrame& frame, bool saturated, hal::CanBus& bus);
#if UWBNAV_COOP
  void send_coop(uint64_t t_us, const NavOutput& nav, hal::CanBus& bus);
#endif

  bool enabled_ = true;
  Schedule pos_;
  Schedule accuracy_{2 * kCanTickUs, 0, false};
  Schedule diag_{10 * kCanTickUs, 0, false};
#if UWBNAV_COOP
  Schedule coop_{10 * kCanTickUs, 0, false};
  uint16_t coop_id_ = kNoVehicleId;
  bool coop_pending_ = false;  // coop_state_ was set for this cycle
  NeighbourState coop_state_;
#endif
  uint8_t counters_[kNumSlots] = {};
  CanTxStats stats_;
};

// Builds the typed messages the publisher sends from one NavOutput/CanDiag.
PosXYMsg pos_xy_from(const NavOutput& nav);
PosZMsg pos_z_from(const NavOutput& nav);
VelHdgMsg vel_hdg_from(const NavOutput& nav);
AccuracyMsg accuracy_from(const NavOutput& nav);
AttitudeMsg attitude_from(const NavOutput& nav);
DiagMsg diag_from(const CanDiag& diag);

#if UWBNAV_COOP
// This vehicle's broadcast state from its navigation output: the tag antenna at
// body lever arm tag_lever_body_m (FLU) is at pos + R(q_nav_body) * lever; the
// covariance is the body origin's (pos_sigma_m, pos_xy_corr; xz = yz = 0: the
// attitude uncertainty's share through the lever is not added); the velocity is
// the body origin's (the lever's rotational velocity omega x lever is ignored:
// below 0.1 m/s for a 1 m lever at 0.1 rad/s); t_us = rx_t_us = nav.t_us.
NeighbourState coop_state_from(const NavOutput& nav, const Vec3f& tag_lever_body_m, uint16_t vehicle_id,
                               bool cooperative);
#endif

}  // namespace uwbnav::can
