// Host replay sources: hand out recorded samples whose timestamp is due.
#include "hal/host/replay_sources.hpp"

namespace uwbnav::hal {

Status ReplayImuSource::poll(uint64_t up_to_us, ImuSample& out) {
  if (finished()) return Status::kEmpty;
  const ImuSample& s = (*samples_)[next_];
  if (s.t_us > up_to_us) return Status::kEmpty;
  out = s;
  ++next_;
  return Status::kOk;
}

Status ReplayUwbSource::poll(uint64_t up_to_us, UwbRange& out) {
  if (finished()) return Status::kEmpty;
  const UwbRange& r = at(next_);
  if (r.t_us > up_to_us) return Status::kEmpty;
  out = r;
  ++next_;
  return Status::kOk;
}

Status ReplayGnssSource::poll(uint64_t up_to_us, GnssFix& out) {
  if (finished()) return Status::kEmpty;
  const GnssFix& f = (*fixes_)[next_];
  if (f.rx_t_us > up_to_us) return Status::kEmpty;
  out = f;
  ++next_;
  return Status::kOk;
}

Status ReplayNeighbourSource::poll(uint64_t up_to_us, NeighbourState& out) {
  if (finished()) return Status::kEmpty;
  const NeighbourState& n = (*states_)[next_];
  if (n.rx_t_us > up_to_us) return Status::kEmpty;
  out = n;
  ++next_;
  return Status::kOk;
}

}  // namespace uwbnav::hal
