// Minimal in-memory board for the libFuzzer targets that drive the whole App
// (console, sensor sequences): sensor sources fed from vectors, a CAN bus that
// accepts and drops, a serial port over a string, a lockstep clock and a
// parameter store. No hal/host dependency so the fuzz build stays small.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "firmware/app.hpp"
#include "hal/hal.hpp"

namespace uwbnav::fuzz {

class VectorImuSource final : public hal::ImuSource {
 public:
  std::vector<ImuSample> samples;
  size_t next = 0;
  Status poll(uint64_t up_to_us, ImuSample& out) override {
    if (next >= samples.size() || samples[next].t_us > up_to_us) return Status::kEmpty;
    out = samples[next++];
    return Status::kOk;
  }
  bool finished() const override { return next >= samples.size(); }
};

class VectorUwbSource final : public hal::UwbSource {
 public:
  std::vector<UwbRange> ranges;
  size_t next = 0;
  Status poll(uint64_t up_to_us, UwbRange& out) override {
    if (next >= ranges.size() || ranges[next].t_us > up_to_us) return Status::kEmpty;
    out = ranges[next++];
    return Status::kOk;
  }
  bool finished() const override { return next >= ranges.size(); }
};

// GNSS fixes in vector order, each due at its arrival time (rx_t_us).
class VectorGnssSource final : public hal::GnssSource {
 public:
  std::vector<GnssFix> fixes;
  size_t next = 0;
  Status poll(uint64_t up_to_us, GnssFix& out) override {
    if (next >= fixes.size() || fixes[next].rx_t_us > up_to_us) return Status::kEmpty;
    out = fixes[next++];
    return Status::kOk;
  }
  bool finished() const override { return next >= fixes.size(); }
};

#if UWBNAV_COOP
// Neighbour states in vector order, each due at its arrival time (rx_t_us).
class VectorNeighbourSource final : public hal::NeighbourSource {
 public:
  std::vector<NeighbourState> states;
  size_t next = 0;
  Status poll(uint64_t up_to_us, NeighbourState& out) override {
    if (next >= states.size() || states[next].rx_t_us > up_to_us) return Status::kEmpty;
    out = states[next++];
    return Status::kOk;
  }
  bool finished() const override { return next >= states.size(); }
};
#endif

class SinkCanBus final : public hal::CanBus {
 public:
  Status send(const hal::CanFrame&) override {
    ++counters_.tx_ok;
    return Status::kOk;
  }
  Status receive(hal::CanFrame&) override { return Status::kEmpty; }
  hal::CanBusState state() const override { return hal::CanBusState::kErrorActive; }
  const hal::CanCounters& counters() const override { return counters_; }
  void reset_counters() override { counters_ = hal::CanCounters{}; }

 private:
  hal::CanCounters counters_;
};

class StringSerial final : public hal::SerialPort {
 public:
  std::string input;
  size_t in_pos = 0;
  size_t written = 0;
  size_t read(uint8_t* buf, size_t cap) override {
    const size_t n = cap < input.size() - in_pos ? cap : input.size() - in_pos;
    if (n > 0) std::memcpy(buf, input.data() + in_pos, n);
    in_pos += n;
    return n;
  }
  size_t write(const uint8_t*, size_t len) override {
    written += len;
    return len;
  }
};

class StepClock final : public hal::Clock {
 public:
  uint64_t now = 0;
  uint64_t now_us() override { return now; }
  void sleep_until_us(uint64_t deadline_us) override {
    if (deadline_us > now) now = deadline_us;
  }
};

// Holds one blob (what "flash" contains); save() replaces it.
class BlobParamStore final : public hal::ParamStore {
 public:
  std::vector<uint8_t> blob;
  bool present = false;
  Status load(uint8_t* buf, size_t cap, size_t* len) override {
    if (!present) return Status::kEmpty;
    if (blob.size() > cap) return Status::kInvalidArgument;
    if (!blob.empty()) std::memcpy(buf, blob.data(), blob.size());
    *len = blob.size();
    return Status::kOk;
  }
  Status save(const uint8_t* buf, size_t len) override {
    blob.assign(buf, buf + len);
    present = true;
    return Status::kOk;
  }
};

// Four anchors on a 30 m square at 2 m height (ids 1..4), one tag (id 0) 1 m up.
inline SiteConfig square_site(bool has_imu, Platform platform) {
  SiteConfig site;
  const float xy[4][2] = {{0.0F, 0.0F}, {30.0F, 0.0F}, {30.0F, 30.0F}, {0.0F, 30.0F}};
  for (size_t i = 0; i < 4; ++i) {
    site.anchors[i].id = static_cast<uint16_t>(i + 1);
    site.anchors[i].pos_nav_m = Vec3f{xy[i][0], xy[i][1], 2.0F};
  }
  site.num_anchors = 4;
  site.tags[0].id = 0;
  site.tags[0].lever_body_m = Vec3f{0.0F, 0.0F, 1.0F};
  site.num_tags = 1;
  site.has_imu = has_imu;
  site.platform = platform;
  return site;
}

// Reads fixed-size fields off the fuzz input; zeros once it is exhausted.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : p_(data), left_(size) {}
  size_t left() const { return left_; }
  uint8_t u8() {
    if (left_ == 0) return 0;
    --left_;
    return *p_++;
  }
  uint16_t u16() { return static_cast<uint16_t>(u8() | (u8() << 8)); }
  uint32_t u32() { return static_cast<uint32_t>(u16()) | (static_cast<uint32_t>(u16()) << 16); }
  float f32_bits() {
    const uint32_t b = u32();
    float f = 0.0F;
    std::memcpy(&f, &b, sizeof f);
    return f;
  }

 private:
  const uint8_t* p_;
  size_t left_;
};

}  // namespace uwbnav::fuzz
