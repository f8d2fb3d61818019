// Clock-mapped replay sources (see clock_mapped_sources.hpp).
#include "tools/hil/clock_mapped_sources.hpp"

namespace uwbnav::hil {

Status ClockMappedImuSource::poll(uint64_t up_to_us, ImuSample& out) {
  if (inner_.finished()) return Status::kEmpty;
  const uint64_t t_clock_us = map_.to_clock_us(inner_.next_t_us());
  if (t_clock_us > up_to_us) return Status::kEmpty;
  const Status s = inner_.poll(UINT64_MAX, out);
  if (ok(s)) out.t_us = t_clock_us;
  return s;
}

Status ClockMappedUwbSource::poll(uint64_t up_to_us, UwbRange& out) {
  if (inner_.finished()) return Status::kEmpty;
  const uint64_t t_clock_us = map_.to_clock_us(inner_.next_t_us());
  if (t_clock_us > up_to_us) return Status::kEmpty;
  const Status s = inner_.poll(UINT64_MAX, out);
  if (ok(s)) out.t_us = t_clock_us;
  return s;
}

namespace {

// Late inputs (GNSS fixes, neighbour states) become due at their arrival on
// the rig's clock and keep their latency: both times are mapped.
template <typename Inner, typename T>
Status poll_at_arrival(Inner& inner, const TimeMap& map, uint64_t up_to_us, T& out) {
  if (inner.finished()) return Status::kEmpty;
  const uint64_t rx_clock_us = map.to_clock_us(inner.next_rx_t_us());
  if (rx_clock_us > up_to_us) return Status::kEmpty;
  const Status s = inner.poll(UINT64_MAX, out);
  if (ok(s)) {
    out.t_us = map.to_clock_us(out.t_us);
    out.rx_t_us = rx_clock_us;
  }
  return s;
}

}  // namespace

Status ClockMappedGnssSource::poll(uint64_t up_to_us, GnssFix& out) {
  return poll_at_arrival(inner_, map_, up_to_us, out);
}

Status ClockMappedNeighbourSource::poll(uint64_t up_to_us, NeighbourState& out) {
  return poll_at_arrival(inner_, map_, up_to_us, out);
}

}  // namespace uwbnav::hil
