// Parameter table and a fixed-size store of current values, bounds-checked on
// every write. One table (estimator/params_table.inc) for the whole firmware.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "estimator/status.hpp"

namespace uwbnav {

// Default of ekf.rbf_bridge (0 off); a board build may switch the network on
// by default to measure its cost (hal/mps2 UWBNAV_MPS2_RBF_BRIDGE=2).
#ifndef UWBNAV_RBF_BRIDGE_DEFAULT
#define UWBNAV_RBF_BRIDGE_DEFAULT 0.0F
#endif

// GNSS fusion (estimator/mm_gnss.cpp). Boards without a receiver and short of
// flash build without it (hal/mps2: UWBNAV_GNSS=0; its parameters are then absent).
#ifndef UWBNAV_GNSS
#define UWBNAV_GNSS 1
#endif

// Cooperative ranging to neighbour vehicles (estimator/navigator_coop.cpp, the
// UWBNAV_Coop* CAN frames). hal/mps2 builds without it (UWBNAV_COOP=0).
#ifndef UWBNAV_COOP
#define UWBNAV_COOP 1
#endif

enum class ParamId : uint16_t {
#define X(e, id, name, unit, kind, def, lo, hi, doc) e,
#include "estimator/params_table.inc"
#undef X
  kCount
};

// What values a parameter takes: any real in [min, max], or whole numbers only
// (counts and durations, booleans 0/1, enumerations). Fractions of the whole
// kinds are refused by Params::set, so the CLI, the console and the blob loader agree.
enum class ParamKind : uint8_t { kReal = 0, kInt = 1, kBool = 2, kEnum = 3 };

constexpr const char* param_kind_name(ParamKind k) {
  switch (k) {
    case ParamKind::kReal: return "real";
    case ParamKind::kInt: return "integer";
    case ParamKind::kBool: return "bool";
    case ParamKind::kEnum: return "enum";
  }
  return "unknown";
}

struct ParamDef {
  ParamId index;
  uint16_t stable_id;  // never reused; what the NV store keys on
  const char* name;    // dotted, lower case; what the console and files use
  const char* unit;
  ParamKind kind;
  float def;
  float min;
  float max;
  const char* doc;
};

constexpr size_t kNumParams = static_cast<size_t>(ParamId::kCount);

// Boards short of flash build without the description texts (UWBNAV_PARAM_DOCS=0,
// e.g. hal/mps2): `doc` is then empty and the console leaves it out.
#ifndef UWBNAV_PARAM_DOCS
#define UWBNAV_PARAM_DOCS 1
#endif
#if UWBNAV_PARAM_DOCS
#define UWBNAV_PARAM_DOC(text) text
#else
#define UWBNAV_PARAM_DOC(text) ""
#endif

// inline: one copy in the image, not one per translation unit that reads it.
inline constexpr ParamDef kParamDefs[kNumParams] = {
#define X(e, id, name, unit, kind, def, lo, hi, doc) \
  {ParamId::e, id, name, unit, ParamKind::kind, def, lo, hi, UWBNAV_PARAM_DOC(doc)},
#include "estimator/params_table.inc"
#undef X
};

namespace detail {
// Whole number test usable in constant expressions. Every finite float of
// magnitude >= 2^24 is whole; below, the int32 round trip is exact.
constexpr bool is_whole(float v) {
  constexpr float k2p24 = 16777216.0F;
  if (!(v == v)) return false;  // NaN
  if (v >= k2p24 || v <= -k2p24) return v < 3.4e38F && v > -3.4e38F;
  return static_cast<float>(static_cast<int32_t>(v)) == v;
}
constexpr bool params_consistent() {
  for (size_t i = 0; i < kNumParams; ++i) {
    const ParamDef& d = kParamDefs[i];
    if (static_cast<size_t>(d.index) != i) return false;
    if (!(d.min <= d.def && d.def <= d.max)) return false;
    if (d.kind != ParamKind::kReal && !(is_whole(d.def) && is_whole(d.min) && is_whole(d.max))) return false;
    if (d.kind == ParamKind::kBool && !(d.min == 0.0F && d.max == 1.0F)) return false;
    for (size_t j = i + 1; j < kNumParams; ++j) {
      if (kParamDefs[j].stable_id == d.stable_id) return false;
    }
  }
  return true;
}
}  // namespace detail
static_assert(detail::params_consistent(),
              "parameter table: default outside [min,max], duplicate stable id, or a whole-number kind with fractional bounds");

// Current parameter values. Plain array of floats; writes are bounds-checked.
class Params {
 public:
  Params() { reset_all(); }

  float get(ParamId id) const { return values_[static_cast<size_t>(id)]; }
  float operator[](ParamId id) const { return get(id); }

  [[nodiscard]] Status set(ParamId id, float value) {
    const size_t i = static_cast<size_t>(id);
    if (i >= kNumParams) return Status::kNotFound;
    if (!std::isfinite(value)) return Status::kNotFinite;
    if (value < kParamDefs[i].min || value > kParamDefs[i].max) return Status::kOutOfRange;
    if (kParamDefs[i].kind != ParamKind::kReal && !detail::is_whole(value)) return Status::kInvalidArgument;
    values_[i] = value;
    return Status::kOk;
  }

  [[nodiscard]] Status set_by_name(const char* name, float value) {
    const ParamDef* d = find(name);
    if (d == nullptr) return Status::kNotFound;
    return set(d->index, value);
  }

  void reset(ParamId id) { values_[static_cast<size_t>(id)] = kParamDefs[static_cast<size_t>(id)].def; }
  void reset_all() {
    for (size_t i = 0; i < kNumParams; ++i) values_[i] = kParamDefs[i].def;
  }

  static const ParamDef* find(const char* name) {
    for (size_t i = 0; i < kNumParams; ++i) {
      if (std::strcmp(kParamDefs[i].name, name) == 0) return &kParamDefs[i];
    }
    return nullptr;
  }
  static const ParamDef* find_stable(uint16_t stable_id) {
    for (size_t i = 0; i < kNumParams; ++i) {
      if (kParamDefs[i].stable_id == stable_id) return &kParamDefs[i];
    }
    return nullptr;
  }

 private:
  float values_[kNumParams];
};

// A parameter value in microseconds (float) as integer microseconds, truncated;
// 0 for values <= 0 and NaN. Through uint32_t: float -> uint64_t is a libgcc call
// that computes in soft double on the Cortex-M4F. The table bounds every such
// value (seconds parameters times 1e6 included) far below 2^32 us (71 min); the
// clamp keeps the conversion defined anyway.
inline uint64_t param_us(float value_us) {
  constexpr float kMaxUs = 4.0e9F;
  return value_us > 0.0F ? static_cast<uint64_t>(static_cast<uint32_t>(std::fmin(value_us, kMaxUs))) : 0U;
}

}  // namespace uwbnav
