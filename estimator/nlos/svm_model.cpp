// Embedded RBF-SVM evaluator in single precision: checksum, scaling, kernel
// exponential, compensated decision value and libsvm-compatible Platt
// probability (seed 000 §1.2(1), eq. 2).
#include "estimator/nlos/svm_model.hpp"

#include <cmath>
#include <cstring>

namespace uwbnav {

namespace {

constexpr uint32_t kCrcPolyReflected = 0xEDB88320U;

// CRC-32 four bits at a time: the register after shifting the nibble n
// through the bitwise algorithm, for each n (16 x 4 B of flash against 1 KiB
// for the byte table; 2 steps per byte instead of 8).
struct CrcNibbleTable {
  uint32_t v[16] = {};
  constexpr CrcNibbleTable() {
    for (uint32_t n = 0; n < 16U; ++n) {
      uint32_t c = n;
      for (int bit = 0; bit < 4; ++bit) c = (c & 1U) != 0U ? (c >> 1U) ^ kCrcPolyReflected : c >> 1U;
      v[n] = c;
    }
  }
};
constexpr CrcNibbleTable kCrcNibble{};

uint32_t crc_u32(uint32_t crc, uint32_t v, size_t bytes) {
  uint8_t buf[4];
  for (size_t i = 0; i < bytes; ++i) buf[i] = static_cast<uint8_t>((v >> (8U * i)) & 0xFFU);
  return crc32_update(crc, buf, bytes);
}

uint32_t crc_float(uint32_t crc, float v) {
  uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  return crc_u32(crc, bits, 4);
}

// Cephes expf (S. Moshier): exp(x) = 2^n exp(r), n = round(x / ln2), r = x - n ln2 with
// ln2 = C1 + C2 (C1 = 355/512: n C1 is exact for |n| <= 2^15); here x = -a, n = -k.
inline float exp_neg_impl(float a) {
  constexpr float kLog2e = 1.44269504088896341F;
  constexpr float kC1 = 0.693359375F;
  constexpr float kC2 = -2.12194440e-4F;
  // Clamp to 87 (k <= 126: 2^-k stays a normal float; +inf and NaN clamp too) on the bit
  // pattern, monotonic for a >= 0: an integer select, which the vectoriser if-converts
  // (a float compare may trap and is not speculated).
  constexpr int32_t kMaxABits = 0x42AE0000;  // 87.0F
  int32_t a_bits = 0;
  std::memcpy(&a_bits, &a, sizeof(a_bits));
  a_bits = a_bits < kMaxABits ? a_bits : kMaxABits;
  std::memcpy(&a, &a_bits, sizeof(a));
  const int32_t k = static_cast<int32_t>(a * kLog2e + 0.5F);  // a >= 0: round half up
  const float kf = static_cast<float>(k);
  const float r = (kf * kC1 - a) + kf * kC2;  // |r| <= ln2/2; kf C1 - a is exact (Sterbenz)
  float p = 1.9875691500e-4F;
  p = p * r + 1.3981999507e-3F;
  p = p * r + 8.3334519073e-3F;
  p = p * r + 4.1665795894e-2F;
  p = p * r + 1.6666665459e-1F;
  p = p * r + 5.0000001201e-1F;
  const float exp_r = p * (r * r) + r + 1.0F;
  const uint32_t scale_bits = static_cast<uint32_t>(127 - k) << 23U;  // 2^-k
  float scale = 0.0F;
  std::memcpy(&scale, &scale_bits, sizeof(scale));
  return exp_r * scale;
}

// Compensated kernel sum: terms are computed in blocks (a plain loop the host compiler
// vectorises) and accumulated in kLanes independent Kahan lanes.
constexpr size_t kLanes = 8;
constexpr size_t kBlock = 64;  // multiple of kLanes; 256 B of stack

// Kahan (compensated) accumulation of `term` into (sum, comp).
inline void kahan_add(float term, float& sum, float& comp) {
  const float y = term - comp;
  const float s = sum + y;
  comp = (s - sum) - y;
  sum = s;
}

// Terms coef_i K(x, sv_i) = coef_i exp(-gamma |x - sv_i|^2) (seed 000 eq. 2) of support
// vectors [first, first + len) into term[0, len).
template <size_t kNf>
void kernel_terms(const SvmModel& m, const float* x, size_t nf, size_t first, size_t len, float* term) {
  const float* coef = m.coef + first;
  if (kNf == 1) {
    const float* s0 = m.sv[0] + first;
    const float x0 = x[0];
    for (size_t j = 0; j < len; ++j) {
      const float d = x0 - s0[j];
      term[j] = coef[j] * exp_neg_impl(m.gamma * (d * d));
    }
  } else if (kNf == 2) {
    const float* s0 = m.sv[0] + first;
    const float* s1 = m.sv[1] + first;
    const float x0 = x[0];
    const float x1 = x[1];
    for (size_t j = 0; j < len; ++j) {
      const float d0 = x0 - s0[j];
      const float d1 = x1 - s1[j];
      term[j] = coef[j] * exp_neg_impl(m.gamma * (d0 * d0 + d1 * d1));
    }
  } else {
    for (size_t j = 0; j < len; ++j) {
      float d2 = 0.0F;
      for (size_t f = 0; f < nf; ++f) {
        const float d = x[f] - m.sv[f][first + j];
        d2 += d * d;
      }
      term[j] = coef[j] * exp_neg_impl(m.gamma * d2);
    }
  }
}

// Sum of the kernel terms; a feature count known at compile time (kNf 1 or 2; 0: nf)
// lets the term loop vectorise.
template <size_t kNf>
float kernel_sum(const SvmModel& m, const float* x, size_t nf) {
  const size_t n = m.num_sv <= kSvmMaxSupportVectors ? m.num_sv : kSvmMaxSupportVectors;
  float sum[kLanes] = {};
  float comp[kLanes] = {};
  float term[kBlock] = {};
  for (size_t first = 0; first < n; first += kBlock) {
    const size_t len = n - first < kBlock ? n - first : kBlock;
    kernel_terms<kNf>(m, x, nf, first, len, term);
    for (size_t j = len; j < kBlock; ++j) term[j] = 0.0F;
    for (size_t j = 0; j < kBlock; j += kLanes) {
      for (size_t l = 0; l < kLanes; ++l) kahan_add(term[j + l], sum[l], comp[l]);
    }
  }
  float total = 0.0F;
  float total_comp = 0.0F;
  for (size_t l = 0; l < kLanes; ++l) {
    kahan_add(sum[l], total, total_comp);
    kahan_add(-comp[l], total, total_comp);
  }
  return total;
}

}  // namespace

uint32_t crc32_update(uint32_t crc, const uint8_t* data, size_t n) {
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) {
    crc ^= data[i];
    crc = (crc >> 4U) ^ kCrcNibble.v[crc & 0xFU];
    crc = (crc >> 4U) ^ kCrcNibble.v[crc & 0xFU];
  }
  return ~crc;
}

uint32_t svm_model_crc32(const SvmModel& m) {
  uint32_t crc = 0;
  crc = crc_u32(crc, m.version, 4);
  crc = crc_u32(crc, m.feature_set, 1);
  crc = crc_u32(crc, m.num_features, 1);
  crc = crc_u32(crc, m.num_sv, 2);
  crc = crc_u32(crc, static_cast<uint8_t>(m.first_label_nlos), 1);
  crc = crc_float(crc, m.gamma);
  crc = crc_float(crc, m.rho);
  crc = crc_float(crc, m.prob_a);
  crc = crc_float(crc, m.prob_b);
  const size_t nf = m.num_features <= kSvmMaxFeatures ? m.num_features : kSvmMaxFeatures;
  const size_t nsv = m.num_sv <= kSvmMaxSupportVectors ? m.num_sv : kSvmMaxSupportVectors;
  for (size_t f = 0; f < nf; ++f) {
    crc = crc_float(crc, m.scale_min[f]);
    crc = crc_float(crc, m.scale_max[f]);
  }
  for (size_t i = 0; i < nsv; ++i) {
    for (size_t f = 0; f < nf; ++f) crc = crc_float(crc, m.sv[f][i]);
    crc = crc_float(crc, m.coef[i]);
  }
  return crc;
}

Status svm_model_validate(const SvmModel& m) {
  if (m.version != kSvmModelVersion) return Status::kUnsupported;
  const auto set = static_cast<SvmFeatureSet>(m.feature_set);
  if (set != SvmFeatureSet::kRangeRate && set != SvmFeatureSet::kRangeRateSpeed &&
      set != SvmFeatureSet::kChannel) {
    return Status::kUnsupported;
  }
  if (m.num_features != svm_feature_count(set) || m.num_features > kSvmMaxFeatures) {
    return Status::kInvalidArgument;
  }
  if (m.num_sv == 0 || m.num_sv > kSvmMaxSupportVectors) return Status::kOutOfRange;
  if (!(m.gamma > 0.0F) || !std::isfinite(m.gamma) || !std::isfinite(m.rho) ||
      !std::isfinite(m.prob_a) || !std::isfinite(m.prob_b)) {
    return Status::kNotFinite;
  }
  for (size_t f = 0; f < m.num_features; ++f) {
    if (!std::isfinite(m.scale_min[f]) || !std::isfinite(m.scale_max[f]) ||
        m.scale_max[f] < m.scale_min[f]) {
      return Status::kNotFinite;
    }
  }
  for (size_t i = 0; i < m.num_sv; ++i) {
    if (!std::isfinite(m.coef[i])) return Status::kNotFinite;
    for (size_t f = 0; f < m.num_features; ++f) {
      if (!std::isfinite(m.sv[f][i])) return Status::kNotFinite;
    }
  }
  if (svm_model_crc32(m) != m.crc32) return Status::kInvalidArgument;
  return Status::kOk;
}

void svm_scale(const SvmModel& m, const float* raw, float* scaled) {
  for (size_t f = 0; f < m.num_features; ++f) {
    const float lo = m.scale_min[f];
    const float hi = m.scale_max[f];
    if (hi <= lo) {
      scaled[f] = 0.0F;
    } else {
      // svm-scale: lower + (upper - lower) * (x - min) / (max - min), lower -1, upper +1.
      scaled[f] = -1.0F + 2.0F * (raw[f] - lo) / (hi - lo);
    }
  }
}

float svm_exp_neg(float a) { return exp_neg_impl(a); }

float svm_decision_value(const SvmModel& m, const float* scaled) {
  float sum = 0.0F;
  switch (m.num_features) {
    case 1: sum = kernel_sum<1>(m, scaled, 1); break;
    case 2: sum = kernel_sum<2>(m, scaled, 2); break;
    default: sum = kernel_sum<0>(m, scaled, m.num_features <= kSvmMaxFeatures ? m.num_features : 0U); break;
  }
  return sum - m.rho;
}

float svm_label0_probability(const SvmModel& m, float decision_value) {
  // libsvm 3.24 svm_predict_probability, two classes: the pairwise probability of
  // label[0] is the final estimate (no coupling iteration), clipped to [1e-7, 1 - 1e-7].
  // sigmoid_predict 1 / (1 + exp(A f + B)), written to avoid cancellation and overflow.
  constexpr float kMinProb = 1e-7F;
  const float f_apb = decision_value * m.prob_a + m.prob_b;
  float p = 0.0F;
  if (f_apb >= 0.0F) {
    const float e = svm_exp_neg(f_apb);
    p = e / (1.0F + e);
  } else {
    p = 1.0F / (1.0F + svm_exp_neg(-f_apb));
  }
  constexpr float kMaxProb = 1.0F - kMinProb;
  return p < kMinProb ? kMinProb : (p > kMaxProb ? kMaxProb : p);
}

bool svm_build_features(SvmFeatureSet set, float range_rate_mps, float speed_mps, float fp_power_dbm,
                        float rx_power_dbm, float* out) {
  switch (set) {
    case SvmFeatureSet::kRangeRate:
      out[0] = range_rate_mps;
      return std::isfinite(out[0]);
    case SvmFeatureSet::kRangeRateSpeed:
      out[0] = range_rate_mps;
      out[1] = speed_mps;
      return std::isfinite(out[0]) && std::isfinite(out[1]);
    case SvmFeatureSet::kChannel:
      out[0] = rx_power_dbm - fp_power_dbm;
      out[1] = fp_power_dbm;
      return std::isfinite(out[0]) && std::isfinite(out[1]);
  }
  return false;
}

Result<float> svm_nlos_probability(const SvmModel& m, const float* raw) {
  if (m.num_sv == 0 || m.num_features == 0 || m.num_features > kSvmMaxFeatures) {
    return Status::kNotInitialised;
  }
  for (size_t f = 0; f < m.num_features; ++f) {
    if (!std::isfinite(raw[f])) return Status::kNotFinite;
  }
  float scaled[kSvmMaxFeatures] = {};
  svm_scale(m, raw, scaled);
  const float p0 = svm_label0_probability(m, svm_decision_value(m, scaled));
  return m.first_label_nlos != 0 ? p0 : 1.0F - p0;
}

}  // namespace uwbnav
