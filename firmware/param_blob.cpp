// Parameter blob encoding for the non-volatile store (see param_blob.hpp).
#include "firmware/param_blob.hpp"

#include <cstring>

#include "estimator/nlos/svm_model.hpp"

namespace uwbnav {
namespace {

constexpr uint8_t kMagic[4] = {'U', 'N', 'P', '1'};

void put_u16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void put_u32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
uint16_t get_u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t get_u32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}

}  // namespace

// The estimator's CRC-32 (estimator/nlos/svm_model.cpp), from the initial state.
uint32_t crc32_ieee(const uint8_t* data, size_t len) { return crc32_update(0U, data, len); }

size_t param_blob_write(const Params& params, uint8_t* buf, size_t cap) {
  if (cap < kParamBlobMaxBytes) return 0;
  std::memcpy(buf, kMagic, 4);
  put_u16(buf + 4, static_cast<uint16_t>(kNumParams));
  size_t off = 6;
  for (size_t i = 0; i < kNumParams; ++i) {
    put_u16(buf + off, kParamDefs[i].stable_id);
    const float v = params.get(kParamDefs[i].index);
    uint32_t bits = 0;
    std::memcpy(&bits, &v, 4);
    put_u32(buf + off + 2, bits);
    off += 6;
  }
  put_u32(buf + off, crc32_ieee(buf, off));
  return off + 4;
}

Status param_blob_read(const uint8_t* buf, size_t len, Params& params, ParamBlobReport* report) {
  ParamBlobReport rep;
  if (buf == nullptr || len < 10 || std::memcmp(buf, kMagic, 4) != 0) return Status::kInvalidArgument;
  const size_t count = get_u16(buf + 4);
  const size_t body = 6 + count * 6;
  if (len != body + 4) return Status::kInvalidArgument;
  if (crc32_ieee(buf, body) != get_u32(buf + body)) return Status::kInvalidArgument;
  for (size_t i = 0; i < count; ++i) {
    const uint8_t* e = buf + 6 + i * 6;
    const ParamDef* d = Params::find_stable(get_u16(e));
    if (d == nullptr) {
      ++rep.unknown;
      continue;
    }
    const uint32_t bits = get_u32(e + 2);
    float v = 0.0F;
    std::memcpy(&v, &bits, 4);
    if (ok(params.set(d->index, v))) {
      ++rep.applied;
    } else {
      ++rep.rejected;
    }
  }
  if (report != nullptr) *report = rep;
  return Status::kOk;
}

}  // namespace uwbnav
