// Embedded RBF-SVM evaluator: checksum, scaling, decision value and libsvm-
// compatible Platt probability (seed 000 §1.2(1), eq. 2).
#include "estimator/nlos/svm_model.hpp"

#include <cmath>
#include <cstring>

namespace uwbnav {

namespace {

constexpr uint32_t kCrcPolyReflected = 0xEDB88320U;

uint32_t crc_u64(uint32_t crc, uint64_t v, size_t bytes) {
  uint8_t buf[8];
  for (size_t i = 0; i < bytes; ++i) buf[i] = static_cast<uint8_t>((v >> (8U * i)) & 0xFFU);
  return crc32_update(crc, buf, bytes);
}

uint32_t crc_double(uint32_t crc, double v) {
  uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  return crc_u64(crc, bits, 8);
}

uint32_t crc_float(uint32_t crc, float v) {
  uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  return crc_u64(crc, bits, 4);
}

// libsvm sigmoid_predict: 1 / (1 + exp(A f + B)), written to avoid cancellation.
double platt_sigmoid(double decision_value, double a, double b) {
  const double f_apb = decision_value * a + b;
  if (f_apb >= 0.0) return std::exp(-f_apb) / (1.0 + std::exp(-f_apb));
  return 1.0 / (1.0 + std::exp(f_apb));
}

}  // namespace

uint32_t crc32_update(uint32_t crc, const uint8_t* data, size_t n) {
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 1U) != 0U ? (crc >> 1U) ^ kCrcPolyReflected : crc >> 1U;
    }
  }
  return ~crc;
}

uint32_t svm_model_crc32(const SvmModel& m) {
  uint32_t crc = 0;
  crc = crc_u64(crc, m.version, 4);
  crc = crc_u64(crc, m.feature_set, 1);
  crc = crc_u64(crc, m.num_features, 1);
  crc = crc_u64(crc, m.num_sv, 2);
  crc = crc_u64(crc, static_cast<uint8_t>(m.first_label_nlos), 1);
  crc = crc_double(crc, m.gamma);
  crc = crc_double(crc, m.rho);
  crc = crc_double(crc, m.prob_a);
  crc = crc_double(crc, m.prob_b);
  const size_t nf = m.num_features <= kSvmMaxFeatures ? m.num_features : kSvmMaxFeatures;
  const size_t nsv = m.num_sv <= kSvmMaxSupportVectors ? m.num_sv : kSvmMaxSupportVectors;
  for (size_t f = 0; f < nf; ++f) {
    crc = crc_float(crc, m.scale_min[f]);
    crc = crc_float(crc, m.scale_max[f]);
  }
  for (size_t i = 0; i < nsv; ++i) {
    for (size_t f = 0; f < nf; ++f) crc = crc_double(crc, m.sv[i][f]);
    crc = crc_double(crc, m.coef[i]);
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
  if (!(m.gamma > 0.0) || !std::isfinite(m.gamma) || !std::isfinite(m.rho) ||
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
      if (!std::isfinite(m.sv[i][f])) return Status::kNotFinite;
    }
  }
  if (svm_model_crc32(m) != m.crc32) return Status::kInvalidArgument;
  return Status::kOk;
}

void svm_scale(const SvmModel& m, const float* raw, double* scaled) {
  for (size_t f = 0; f < m.num_features; ++f) {
    const double lo = static_cast<double>(m.scale_min[f]);
    const double hi = static_cast<double>(m.scale_max[f]);
    if (hi <= lo) {
      scaled[f] = 0.0;
    } else {
      // svm-scale: lower + (upper - lower) * (x - min) / (max - min), lower -1, upper +1.
      scaled[f] = -1.0 + 2.0 * (static_cast<double>(raw[f]) - lo) / (hi - lo);
    }
  }
}

double svm_decision_value(const SvmModel& m, const double* scaled) {
  double sum = 0.0;
  for (size_t i = 0; i < m.num_sv; ++i) {
    double d2 = 0.0;
    for (size_t f = 0; f < m.num_features; ++f) {
      const double d = scaled[f] - m.sv[i][f];
      d2 += d * d;
    }
    sum += m.coef[i] * std::exp(-m.gamma * d2);  // seed 000 eq. 2
  }
  return sum - m.rho;
}

double svm_label0_probability(const SvmModel& m, double decision_value) {
  // libsvm 3.24 svm_predict_probability, two classes: the pairwise probability of
  // label[0] is the final estimate (no coupling iteration), clipped to [1e-7, 1 - 1e-7].
  constexpr double kMinProb = 1e-7;
  const double p = platt_sigmoid(decision_value, m.prob_a, m.prob_b);
  return std::fmin(std::fmax(p, kMinProb), 1.0 - kMinProb);
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
  double scaled[kSvmMaxFeatures] = {};
  svm_scale(m, raw, scaled);
  const double p0 = svm_label0_probability(m, svm_decision_value(m, scaled));
  const double p_nlos = m.first_label_nlos != 0 ? p0 : 1.0 - p0;
  return static_cast<float>(p_nlos);
}

}  // namespace uwbnav
