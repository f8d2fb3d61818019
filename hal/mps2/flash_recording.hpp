// A format v1 recording compiled into flash: the layout the generator
// (hal/mps2/gen_flash_recording.py) emits and the board's replay sources read.
// Values are bit-identical to what the host reader (tools/dataset) produces
// from the same directory; timestamps are stored as offsets from t_base_us.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav::mps2 {

struct FlashAnchor {
  uint16_t id;
  float pos_nav_m[3];            // navigation frame [m]
};

struct FlashTag {
  uint8_t id;
  float lever_body_m[3];         // body frame FLU [m]
};

struct FlashImu {
  uint32_t dt_us;                // t_us - t_base_us [us]
  float accel_body_mps2[3];      // specific force, body frame [m/s^2]
  float gyro_body_radps[3];      // angular rate, body frame [rad/s]
};

struct FlashUwb {
  uint32_t dt_us;                // t_us - t_base_us [us]
  float range_m;                 // [m]
  float fp_power_dbm;            // NaN when unknown [dBm]
  float rx_power_dbm;            // NaN when unknown [dBm]
  uint16_t anchor_id;
  uint8_t tag_id;
};

constexpr uint8_t kPlatformUnset = 0xFF;  // meta.ini has no platform: SiteConfig default

struct FlashRecording {
  const char* name;              // meta.ini name (or the directory name)
  uint64_t t_base_us;            // time origin of dt_us [us]
  const FlashAnchor* anchors;
  size_t num_anchors;
  const FlashTag* tags;          // at least one (tag 0 at the origin when tags.csv is absent)
  size_t num_tags;
  uint8_t platform;              // Platform value or kPlatformUnset
  float gravity_mps2;            // NaN: meta.ini has none (SiteConfig default)
  const FlashImu* imu;
  size_t num_imu;
  const FlashUwb* uwb;
  size_t num_uwb;
};

// The recording of this image (generated source).
extern const FlashRecording kFlashRecording;

// Fills `site` as dataset::read_recording would from the same directory.
[[nodiscard]] Status load_site(const FlashRecording& rec, SiteConfig& site);

}  // namespace uwbnav::mps2
