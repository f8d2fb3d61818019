// Serialisation of the parameter values for the HAL parameter store: a small
// versioned blob keyed by stable id, protected by a CRC-32.
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/params.hpp"
#include "estimator/status.hpp"

namespace uwbnav {

// Magic "UNP1", u16 count, count x (u16 stable_id, f32 value), u32 CRC-32 (IEEE) of all before.
constexpr size_t kParamBlobMaxBytes = 4 + 2 + kNumParams * 6 + 4;

// Writes all values. Returns the blob length, or 0 when cap is too small.
size_t param_blob_write(const Params& params, uint8_t* buf, size_t cap);

struct ParamBlobReport {
  uint16_t applied = 0;    // values set
  uint16_t unknown = 0;    // stable ids this build does not know (skipped)
  uint16_t rejected = 0;   // values outside [min, max] or not finite (skipped, default kept)
};

// Applies a blob to `params`. kInvalidArgument: bad magic/length/CRC (params untouched).
[[nodiscard]] Status param_blob_read(const uint8_t* buf, size_t len, Params& params, ParamBlobReport* report);

uint32_t crc32_ieee(const uint8_t* data, size_t len);

}  // namespace uwbnav
