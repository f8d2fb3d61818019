// MPS2-AN386 board port (see board.hpp).
#include "hal/mps2/board.hpp"

#include <cmath>

namespace uwbnav::mps2 {

Status load_site(const FlashRecording& rec, SiteConfig& site) {
  site = SiteConfig{};
  for (size_t i = 0; i < rec.num_anchors; ++i) {
    const FlashAnchor& a = rec.anchors[i];
    const Status s = site.add_anchor(a.id, Vec3f{a.pos_nav_m[0], a.pos_nav_m[1], a.pos_nav_m[2]});
    if (!ok(s)) return s;
  }
  for (size_t i = 0; i < rec.num_tags; ++i) {
    const FlashTag& t = rec.tags[i];
    const Status s = site.add_tag(t.id, Vec3f{t.lever_body_m[0], t.lever_body_m[1], t.lever_body_m[2]});
    if (!ok(s)) return s;
  }
  if (rec.platform != kPlatformUnset) site.platform = static_cast<Platform>(rec.platform);
  if (!std::isnan(rec.gravity_mps2)) site.gravity_mps2 = rec.gravity_mps2;
  site.has_imu = rec.num_imu > 0;
  return site.num_anchors > 0 && site.num_tags > 0 ? Status::kOk : Status::kInvalidArgument;
}

Status FlashImuSource::poll(uint64_t up_to_us, ImuSample& out) {
  if (next_ >= rec_.num_imu) return Status::kEmpty;
  const FlashImu& s = rec_.imu[next_];
  const uint64_t t_us = rec_.t_base_us + s.dt_us;
  if (t_us > up_to_us) return Status::kEmpty;
  out.t_us = t_us;
  out.accel_body_mps2 = Vec3f{s.accel_body_mps2[0], s.accel_body_mps2[1], s.accel_body_mps2[2]};
  out.gyro_body_radps = Vec3f{s.gyro_body_radps[0], s.gyro_body_radps[1], s.gyro_body_radps[2]};
  ++next_;
  return Status::kOk;
}

Status FlashUwbSource::poll(uint64_t up_to_us, UwbRange& out) {
  if (next_ >= rec_.num_uwb) return Status::kEmpty;
  const FlashUwb& r = rec_.uwb[next_];
  const uint64_t t_us = rec_.t_base_us + r.dt_us;
  if (t_us > up_to_us) return Status::kEmpty;
  out.t_us = t_us;
  out.anchor_id = r.anchor_id;
  out.tag_id = r.tag_id;
  out.range_m = r.range_m;
  out.fp_power_dbm = r.fp_power_dbm;
  out.rx_power_dbm = r.rx_power_dbm;
  ++next_;
  return Status::kOk;
}

RingCanBus::RingCanBus() = default;

Status RingCanBus::send(const hal::CanFrame& frame) {
  const bool fd = (frame.flags & hal::CanFrame::kFlagFd) != 0;
  if (frame.len > (fd ? 64U : 8U)) return Status::kInvalidArgument;
  if (count_ == kCapacity) {
    ++counters_.tx_dropped;
    return Status::kWouldBlock;
  }
  ring_[(head_ + count_) % kCapacity] = frame;
  ++count_;
  ++counters_.tx_ok;
  return Status::kOk;
}

Status RingCanBus::receive(hal::CanFrame&) { return Status::kEmpty; }

Status RingCanBus::pop_sent(hal::CanFrame& out) {
  if (count_ == 0) return Status::kEmpty;
  out = ring_[head_];
  head_ = (head_ + 1) % kCapacity;
  --count_;
  return Status::kOk;
}

namespace {

// SysTick registers (Armv7-M ARM B3.3).
volatile uint32_t* const kSystCsr = reinterpret_cast<volatile uint32_t*>(0xE000E010U);
volatile uint32_t* const kSystRvr = reinterpret_cast<volatile uint32_t*>(0xE000E014U);
volatile uint32_t* const kSystCvr = reinterpret_cast<volatile uint32_t*>(0xE000E018U);
constexpr uint32_t kCsrEnable = 1U << 0;
constexpr uint32_t kCsrClkSourceCore = 1U << 2;

}  // namespace

void CycleCounter::start() {
  *kSystCsr = 0U;
  *kSystRvr = kMask;
  *kSystCvr = 0U;  // any write clears the counter; it reloads on the next tick
  *kSystCsr = kCsrEnable | kCsrClkSourceCore;
}

uint32_t CycleCounter::now() { return *kSystCvr & kMask; }

uint32_t calibrate_ticks(uint32_t instructions) {
  uint32_t n = instructions / 2U;
  const uint32_t begin = CycleCounter::now();
  __asm__ volatile(
      "1:\n\t"
      "subs %0, %0, #1\n\t"
      "bne 1b"
      : "+r"(n)
      :
      : "cc");
  const uint32_t end = CycleCounter::now();
  return CycleCounter::elapsed(begin, end);
}

}  // namespace uwbnav::mps2
