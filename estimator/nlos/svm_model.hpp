// Embedded RBF-SVM evaluator for NLOS identification (seed 000 §1.2(1), eq. 1-2):
// fixed-capacity single-precision model (svm-scale min/max scaling, support
// vectors, libsvm Platt parameters, CRC-32) and the Platt-scaled NLOS
// probability p1 computed as libsvm 3.24 svm_predict_probability does for two
// classes, in float only (no double arithmetic: the Cortex-M4F has a
// single-precision FPU). Static memory only; cost O(num_sv * num_features).
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/status.hpp"

namespace uwbnav {

constexpr size_t kSvmMaxSupportVectors = 256;  // evaluator capacity; training respects it
// Features per model: the largest feature set below (checked after svm_feature_count).
constexpr size_t kSvmMaxFeatures = 2;
constexpr uint32_t kSvmModelVersion = 2;       // layout/semantics of SvmModel (2: float content)

// What the feature vector of a model means (stable values, stored in the model).
enum class SvmFeatureSet : uint8_t {
  kRangeRate = 1,       // {v_uk [m/s]}                       seed 000 "SVM1"
  kRangeRateSpeed = 2,  // {v_uk [m/s], v_ik [m/s]}           seed 000 "SVM2"
  kChannel = 3,         // {rx-fp power [dB], fp power [dBm]} DW1000 channel diagnostics
};

constexpr size_t svm_feature_count(SvmFeatureSet set) {
  return set == SvmFeatureSet::kRangeRate ? 1U : 2U;
}
static_assert(svm_feature_count(SvmFeatureSet::kRangeRate) <= kSvmMaxFeatures &&
                  svm_feature_count(SvmFeatureSet::kRangeRateSpeed) <= kSvmMaxFeatures &&
                  svm_feature_count(SvmFeatureSet::kChannel) <= kSvmMaxFeatures,
              "kSvmMaxFeatures below a feature set's size");

// One trained two-class C-SVC with RBF kernel K = exp(-gamma |x - x'|^2) (seed 000 eq. 2),
// libsvm's double model rounded to float. Support vectors are stored already scaled to
// [-1, 1] (svm-scale convention), feature-major (sv[f][i]) so the kernel loop vectorises.
struct SvmModel {
  uint32_t version = 0;                 // kSvmModelVersion
  uint8_t feature_set = 0;              // SvmFeatureSet
  uint8_t num_features = 0;             // <= kSvmMaxFeatures
  uint16_t num_sv = 0;                  // <= kSvmMaxSupportVectors
  int8_t first_label_nlos = 0;          // 1 when libsvm's label[0] is the NLOS class (label 1)
  float gamma = 0.0F;                   // RBF gamma on scaled features [-]
  float rho = 0.0F;                     // libsvm rho[0]: decision = sum coef K - rho
  float prob_a = 0.0F;                  // libsvm probA[0] (Platt slope)
  float prob_b = 0.0F;                  // libsvm probB[0] (Platt offset)
  float scale_min[kSvmMaxFeatures] = {};  // feature minimum of the training set (maps to -1)
  float scale_max[kSvmMaxFeatures] = {};  // feature maximum of the training set (maps to +1)
  float sv[kSvmMaxFeatures][kSvmMaxSupportVectors] = {};  // sv[f][i]: scaled feature f of support vector i
  float coef[kSvmMaxSupportVectors] = {};  // libsvm sv_coef[0][i] = y_i alpha_i
  uint32_t crc32 = 0;                   // svm_model_crc32() of everything above
};

// CRC-32 (IEEE 802.3, reflected, init/xorout 0xFFFFFFFF) over a byte buffer.
uint32_t crc32_update(uint32_t crc, const uint8_t* data, size_t n);

// CRC-32 of the model content (the stored float bit patterns) in a fixed little-endian
// serialisation (independent of struct padding and host byte order): version,
// feature_set, num_features, num_sv, first_label_nlos, gamma, rho, prob_a, prob_b,
// (scale_min, scale_max) per feature, then per support vector its features and coef.
// Unused slots are not covered.
uint32_t svm_model_crc32(const SvmModel& model);

// Checks version, sizes, finiteness of the used content and the checksum.
[[nodiscard]] Status svm_model_validate(const SvmModel& model);

// svm-scale style scaling of raw features to [-1, 1] (lower -1, upper +1).
// A feature whose training range is empty maps to 0 (svm-scale drops it).
void svm_scale(const SvmModel& model, const float* raw, float* scaled);

// exp(-a) for a >= 0 in single precision: Cody-Waite reduction a = k ln2 - r (ln2 in
// two parts, k ln2_hi exact), the Cephes expf polynomial (degree 7) for exp(r) on
// |r| <= ln2/2, 2^-k through the exponent bits; about 1 ulp. a >= 87 gives 2^-126 (the kernel is then negligible).
// Branch-free (the kernel loop vectorises on the host), no C library call, the same
// float operations on the host and the target.
float svm_exp_neg(float a);

// libsvm decision value of scaled features: sum_i coef_i K(x, sv_i) - rho, in float with
// compensated (Kahan) summation in 8 lanes: the terms cancel heavily (sum |coef K| reaches
// 1.4e4 for the committed SVM2, C = 128), plain float accumulation would lose 7e-3.
float svm_decision_value(const SvmModel& model, const float* scaled);

// libsvm 3.24 two-class probability of the model's label[0] class from a decision
// value: Platt sigmoid 1 / (1 + exp(A f + B)) clipped to [1e-7, 1 - 1e-7]; for two
// classes libsvm takes the pairwise probability as is (no pairwise coupling).
float svm_label0_probability(const SvmModel& model, float decision_value);

// NLOS probability p1 of raw (unscaled) features. kNotFinite for NaN/Inf features,
// kNotInitialised for a model that has no support vectors.
[[nodiscard]] Result<float> svm_nlos_probability(const SvmModel& model, const float* raw);

// Feature vector of a feature set from the quantities available per range.
// range_rate_mps: v_uk of seed 000 eq. 1 [m/s]; speed_mps: v_ik [m/s];
// powers [dBm]. Returns false when a needed input is not finite.
bool svm_build_features(SvmFeatureSet set, float range_rate_mps, float speed_mps, float fp_power_dbm,
                        float rx_power_dbm, float* out);

// Committed default models (estimator/nlos/svm_model_default.cpp, generated).
extern const SvmModel kSvmModelRangeRate;       // SVM1
extern const SvmModel kSvmModelRangeRateSpeed;  // SVM2 (the default)

}  // namespace uwbnav
