// Protects the embedded single-precision SVM evaluator: probability equal to
// libsvm 3.24 svm_predict_probability (double model) to 1e-5, decision values and
// the float kernel exponential within measured float error, the committed default
// models against libsvm on their own float values, checksum verification, the
// committed models' integrity and their generated file matching the exporter.
#include <svm.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "estimator/nlos/svm_model.hpp"
#include "tools/eval/svm_train.hpp"

namespace uwbnav {
namespace {

void quiet(const char*) {}

// Two overlapping Gaussian classes in feature space (range rate, speed); label 1 = NLOS.
std::vector<eval::SvmSample> make_samples(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0F, 1.0F);
  std::vector<eval::SvmSample> out;
  for (size_t i = 0; i < n; ++i) {
    eval::SvmSample s;
    s.label = static_cast<int>(i % 2);
    const float shift = s.label != 0 ? 8.0F : 0.0F;
    s.features[0] = shift + 10.0F * noise(rng);
    s.features[1] = 5.0F + 3.0F * noise(rng);
    out.push_back(s);
  }
  return out;
}

struct TrainedPair {
  SvmModel embedded;
  svm_model* libsvm = nullptr;  // its SV pointers point into `nodes`
  std::vector<svm_node> nodes;
  std::vector<svm_node*> rows;
  std::vector<double> y;
};

// Trains with libsvm directly and converts with the same scaling the tool uses.
TrainedPair train_pair(const std::vector<eval::SvmSample>& train, double c, double gamma) {
  TrainedPair tp;
  eval::SvmTrainOptions opt;
  opt.set = SvmFeatureSet::kRangeRateSpeed;
  opt.c_grid = {c};
  opt.gamma_grid = {gamma};
  opt.grid_samples = train.size();
  opt.max_train_samples = train.size();
  eval::SvmTrainReport report;
  std::string err;
  EXPECT_TRUE(ok(eval::train_svm_model(train, opt, tp.embedded, report, &err))) << err;
  // Same training set and rand() seed as train_svm_model's final fit: the libsvm twin.
  std::vector<svm_node>& nodes = tp.nodes;
  std::vector<svm_node*>& rows = tp.rows;
  std::vector<double>& y = tp.y;
  nodes.resize(train.size() * 3);
  rows.resize(train.size());
  y.resize(train.size());
  for (size_t i = 0; i < train.size(); ++i) {
    double x[kSvmMaxFeatures] = {};
    eval::svm_scale_double(tp.embedded, train[i].features, x);
    nodes[3 * i] = svm_node{1, x[0]};
    nodes[3 * i + 1] = svm_node{2, x[1]};
    nodes[3 * i + 2] = svm_node{-1, 0.0};
    rows[i] = &nodes[3 * i];
    y[i] = train[i].label;
  }
  svm_problem prob{static_cast<int>(train.size()), y.data(), rows.data()};
  svm_parameter param{};
  param.svm_type = C_SVC;
  param.kernel_type = RBF;
  param.gamma = gamma;
  param.C = c;
  param.cache_size = 100;
  param.eps = 1e-3;
  param.shrinking = 1;
  param.probability = 1;
  svm_set_print_string_function(quiet);
  std::srand(static_cast<unsigned>(opt.seed));
  tp.libsvm = svm_train(&prob, &param);
  return tp;
}

// A libsvm model holding an embedded model's float values (exactly, as double): libsvm's
// double arithmetic on the same model, isolating the float arithmetic of the evaluator.
struct LibsvmView {
  svm_model model{};
  std::vector<svm_node> nodes;
  std::vector<svm_node*> rows;
  std::vector<double> coef;
  double* coef_rows[1] = {nullptr};
  double rho = 0.0, prob_a = 0.0, prob_b = 0.0;
  int label[2] = {0, 0};
  int nsv[2] = {0, 0};
};

void view_of(const SvmModel& m, LibsvmView& v) {
  const size_t nf = m.num_features;
  v.nodes.resize(m.num_sv * (nf + 1));
  v.rows.resize(m.num_sv);
  v.coef.resize(m.num_sv);
  for (size_t i = 0; i < m.num_sv; ++i) {
    for (size_t f = 0; f < nf; ++f) {
      v.nodes[i * (nf + 1) + f] = svm_node{static_cast<int>(f + 1), static_cast<double>(m.sv[f][i])};
    }
    v.nodes[i * (nf + 1) + nf] = svm_node{-1, 0.0};
    v.rows[i] = &v.nodes[i * (nf + 1)];
    v.coef[i] = static_cast<double>(m.coef[i]);
    ++v.nsv[m.coef[i] > 0.0F ? 0 : 1];  // libsvm orders the label[0] SVs (coef > 0) first
  }
  v.coef_rows[0] = v.coef.data();
  v.rho = static_cast<double>(m.rho);
  v.prob_a = static_cast<double>(m.prob_a);
  v.prob_b = static_cast<double>(m.prob_b);
  v.label[0] = m.first_label_nlos != 0 ? 1 : 0;
  v.label[1] = 1 - v.label[0];
  v.model.param.svm_type = C_SVC;
  v.model.param.kernel_type = RBF;
  v.model.param.gamma = static_cast<double>(m.gamma);
  v.model.nr_class = 2;
  v.model.l = m.num_sv;
  v.model.SV = v.rows.data();
  v.model.sv_coef = v.coef_rows;
  v.model.rho = &v.rho;
  v.model.probA = &v.prob_a;
  v.model.probB = &v.prob_b;
  v.model.label = v.label;
  v.model.nSV = v.nsv;
  v.model.free_sv = 0;
}

struct ParityStats {
  double max_dp = 0.0;   // max |p_embedded - p_libsvm|
  double max_df = 0.0;   // max |f_embedded - f_libsvm|
  double max_cond = 0.0; // max sum_i |coef_i K_i| (cancellation in the decision value)
};

// Embedded probability/decision vs libsvm's svm_predict_probability / svm_predict_values
// on `lib` (a double model) at raw feature vectors `pts`.
ParityStats compare(const SvmModel& m, const svm_model* lib, const std::vector<std::vector<float>>& pts) {
  ParityStats st;
  int labels[2];
  svm_get_labels(lib, labels);
  for (const auto& raw : pts) {
    double x[kSvmMaxFeatures] = {};
    eval::svm_scale_double(m, raw.data(), x);
    svm_node nodes[kSvmMaxFeatures + 1];
    for (size_t f = 0; f < m.num_features; ++f) nodes[f] = svm_node{static_cast<int>(f + 1), x[f]};
    nodes[m.num_features] = svm_node{-1, 0.0};
    double pe[2] = {0.0, 0.0};
    svm_predict_probability(lib, nodes, pe);
    const double p_lib = labels[0] == 1 ? pe[0] : pe[1];
    const Result<float> p = svm_nlos_probability(m, raw.data());
    EXPECT_TRUE(p.ok());
    st.max_dp = std::fmax(st.max_dp, std::fabs(static_cast<double>(p.value()) - p_lib));
    double dec = 0.0;
    svm_predict_values(lib, nodes, &dec);
    float xf[kSvmMaxFeatures] = {};
    svm_scale(m, raw.data(), xf);
    st.max_df = std::fmax(st.max_df, std::fabs(static_cast<double>(svm_decision_value(m, xf)) - dec));
    double cond = 0.0;
    for (size_t i = 0; i < m.num_sv; ++i) {
      double d2 = 0.0;
      for (size_t f = 0; f < m.num_features; ++f) {
        const double d = x[f] - static_cast<double>(m.sv[f][i]);
        d2 += d * d;
      }
      cond += std::fabs(static_cast<double>(m.coef[i])) * std::exp(-static_cast<double>(m.gamma) * d2);
    }
    st.max_cond = std::fmax(st.max_cond, cond);
  }
  return st;
}

TEST(SvmParity, EmbeddedProbabilityMatchesLibsvmPredictProbabilityTo1e5) {
  // libsvm evaluates its own double model; the embedded model is that model rounded to float.
  const auto train = make_samples(300, 7);
  const auto test = make_samples(2000, 99);
  TrainedPair tp = train_pair(train, 4.0, 2.0);
  ASSERT_NE(tp.libsvm, nullptr);
  ASSERT_EQ(svm_get_nr_sv(tp.libsvm), tp.embedded.num_sv);
  ASSERT_EQ(static_cast<float>(tp.libsvm->rho[0]), tp.embedded.rho);
  ASSERT_EQ(static_cast<float>(tp.libsvm->sv_coef[0][0]), tp.embedded.coef[0]);
  ASSERT_EQ(static_cast<float>(tp.libsvm->SV[0][0].value), tp.embedded.sv[0][0]);
  ASSERT_EQ(static_cast<float>(tp.libsvm->SV[0][1].value), tp.embedded.sv[1][0]);
  std::vector<std::vector<float>> pts;
  for (const auto& s : test) pts.push_back({s.features[0], s.features[1]});
  const ParityStats st = compare(tp.embedded, tp.libsvm, pts);
  std::printf("synthetic model (C 4, gamma 2, %d SVs): max |dp| %.3g, max |df| %.3g, max sum|coef K| %.3g\n",
              tp.embedded.num_sv, st.max_dp, st.max_df, st.max_cond);
  EXPECT_LT(st.max_dp, 1e-5);  // measured 1.2e-6
  // Model rounding plus float arithmetic: a few float roundings of the largest sum
  // sum |coef K| (measured 5.0e-6 in f at sum 606, bound 5.8e-4).
  const double eps_f = static_cast<double>(std::numeric_limits<float>::epsilon());
  EXPECT_LT(st.max_df, 8.0 * eps_f * st.max_cond);
  svm_free_and_destroy_model(&tp.libsvm);
}

// Raw feature grid over the committed models' training range.
std::vector<std::vector<float>> feature_grid(size_t nf) {
  std::vector<std::vector<float>> pts;
  for (int i = 0; i <= 16000; ++i) {
    const float rate_mps = -40.0F + 0.005F * static_cast<float>(i);
    if (nf == 1) {
      pts.push_back({rate_mps});
    } else {
      for (int j = 0; j <= 20; j += 2) pts.push_back({rate_mps, static_cast<float>(j)});
    }
  }
  return pts;
}

TEST(SvmParity, CommittedModelsMatchLibsvmOnTheirFloatValues) {
  // The float arithmetic alone (libsvm evaluates the same float values in double). SVM2
  // (C = 128) sums up to 6.3e3 in |coef K| on this grid to decision values of order 1:
  // rounding each K to float alone costs up to 9e-5 in f, i.e. 8e-6 in p (|A|/4 = 0.093).
  // Measured: SVM1 6.2e-7 in p (2.0e-6 in f), SVM2 1.12e-5 in p (1.22e-4 in f); rounding
  // the model itself to float moves p by at most 2.4e-6.
  for (const SvmModel* m : {&kSvmModelRangeRate, &kSvmModelRangeRateSpeed}) {
    LibsvmView v;
    view_of(*m, v);
    ASSERT_EQ(svm_check_probability_model(&v.model), 1);
    const ParityStats st = compare(*m, &v.model, feature_grid(m->num_features));
    std::printf("committed model %d (%d SVs): max |dp| %.3g, max |df| %.3g, max sum|coef K| %.3g\n",
                m->feature_set, m->num_sv, st.max_dp, st.max_df, st.max_cond);
    const double eps_f = static_cast<double>(std::numeric_limits<float>::epsilon());
    EXPECT_LT(st.max_df, 8.0 * eps_f * st.max_cond);  // a few float roundings of the largest sum
    EXPECT_LT(st.max_dp, m->feature_set == 1 ? 1e-6 : 2e-5);
  }
}

TEST(SvmExpNeg, WithinTwoUlpOfExpOverKernelRange) {
  double max_rel = 0.0;
  for (int i = 0; i <= 200000; ++i) {
    const float a = 0.0004F * static_cast<float>(i);  // 0 .. 80
    const double ref = std::exp(-static_cast<double>(a));
    max_rel = std::fmax(max_rel, std::fabs(static_cast<double>(svm_exp_neg(a)) - ref) / ref);
  }
  EXPECT_LT(max_rel, 2.0 * static_cast<double>(std::numeric_limits<float>::epsilon()));
  EXPECT_EQ(svm_exp_neg(0.0F), 1.0F);
  EXPECT_GT(svm_exp_neg(1e30F), 0.0F);  // clamped, no underflow to a denormal or NaN
  EXPECT_LT(svm_exp_neg(std::numeric_limits<float>::infinity()), 1e-37F);
}

TEST(SvmParity, TwoClassProbabilityIsClippedSigmoidWithoutCoupling) {
  // libsvm 3.24 returns the Platt sigmoid for two classes; the multi-class coupling
  // iteration would stop at exactly 0.5 here (its tolerance is 0.0025).
  SvmModel m;
  m.prob_a = -1.0F;
  m.prob_b = 0.0F;
  EXPECT_NEAR(static_cast<double>(svm_label0_probability(m, 0.01F)), 1.0 / (1.0 + std::exp(-0.01)), 1e-7);
  EXPECT_NEAR(static_cast<double>(svm_label0_probability(m, -3.0F)), 1.0 / (1.0 + std::exp(3.0)), 1e-8);
  EXPECT_EQ(svm_label0_probability(m, 40.0F), 1.0F - 1e-7F);
  EXPECT_EQ(svm_label0_probability(m, -40.0F), 1e-7F);
  EXPECT_EQ(svm_label0_probability(m, 1e30F), 1.0F - 1e-7F);  // no overflow in the sigmoid
}

TEST(SvmModelChecksum, CorruptedCoefficientIsDetected) {
  const auto train = make_samples(200, 3);
  TrainedPair tp = train_pair(train, 2.0, 1.0);
  svm_free_and_destroy_model(&tp.libsvm);
  ASSERT_TRUE(ok(svm_model_validate(tp.embedded)));
  SvmModel bad = tp.embedded;
  bad.coef[0] = std::nextafter(bad.coef[0], 1e30F);  // one ulp
  EXPECT_EQ(svm_model_validate(bad), Status::kInvalidArgument);
  bad = tp.embedded;
  bad.version = kSvmModelVersion + 1;
  EXPECT_EQ(svm_model_validate(bad), Status::kUnsupported);
  bad = tp.embedded;
  bad.num_sv = 0;
  EXPECT_EQ(svm_model_validate(bad), Status::kOutOfRange);
}

TEST(SvmModelDefault, CommittedModelsPassValidationAndFitCapacity) {
  EXPECT_TRUE(ok(svm_model_validate(kSvmModelRangeRate)));
  EXPECT_TRUE(ok(svm_model_validate(kSvmModelRangeRateSpeed)));
  EXPECT_EQ(kSvmModelRangeRate.feature_set, static_cast<uint8_t>(SvmFeatureSet::kRangeRate));
  EXPECT_EQ(kSvmModelRangeRateSpeed.feature_set, static_cast<uint8_t>(SvmFeatureSet::kRangeRateSpeed));
  EXPECT_LE(kSvmModelRangeRateSpeed.num_sv, kSvmMaxSupportVectors);
}

TEST(SvmModelDefault, RangeRateSpeedModelSeparatesObviousCases) {
  // A LOS range rate within the vehicle speed vs a +1.5 m jump in 80 ms (seed 000 protocol).
  const float los[2] = {-3.0F, 5.0F};
  const float nlos[2] = {18.0F, 5.0F};
  const Result<float> p_los = svm_nlos_probability(kSvmModelRangeRateSpeed, los);
  const Result<float> p_nlos = svm_nlos_probability(kSvmModelRangeRateSpeed, nlos);
  ASSERT_TRUE(p_los.ok());
  ASSERT_TRUE(p_nlos.ok());
  EXPECT_LT(p_los.value(), 0.5F);
  EXPECT_GT(p_nlos.value(), 0.8F);
}

TEST(SvmModelDefault, NonFiniteFeatureIsRejected) {
  const float bad[2] = {std::nanf(""), 1.0F};
  EXPECT_EQ(svm_nlos_probability(kSvmModelRangeRateSpeed, bad).status(), Status::kNotFinite);
}

TEST(SvmModelDefault, CommittedFileIsWhatTheExporterWritesForTheseModels) {
  // The committed file was converted from the version-1 export (values rounded to float);
  // it must be byte-identical to what `uwbnav train-svm` writes for the same values.
  std::ifstream in(std::string(UWBNAV_SOURCE_DIR) + "/estimator/nlos/svm_model_default.cpp");
  ASSERT_TRUE(in.good());
  std::stringstream committed;
  committed << in.rdbuf();
  const std::string exported = eval::export_models_cpp({kSvmModelRangeRate, kSvmModelRangeRateSpeed},
                                                       {"kSvmModelRangeRate", "kSvmModelRangeRateSpeed"},
                                                       {eval::SvmTrainReport{}, eval::SvmTrainReport{}}, "test");
  const std::string from = "#include \"estimator/nlos/svm_model.hpp\"";
  ASSERT_NE(committed.str().find(from), std::string::npos);
  EXPECT_EQ(committed.str().substr(committed.str().find(from)), exported.substr(exported.find(from)));
  EXPECT_NE(committed.str().find("do not edit"), std::string::npos);
}

TEST(Crc32, NibbleTableMatchesTheBitwiseDefinitionForEveryByteAndChunking) {
  // Reference: the reflected CRC-32 one bit at a time (what the nibble table
  // of svm_model.cpp precomputes).
  auto bitwise = [](uint32_t crc, const uint8_t* d, size_t n) {
    crc = ~crc;
    for (size_t i = 0; i < n; ++i) {
      crc ^= d[i];
      for (int b = 0; b < 8; ++b) crc = (crc & 1U) != 0U ? (crc >> 1U) ^ 0xEDB88320U : crc >> 1U;
    }
    return ~crc;
  };
  uint8_t all[256];
  for (int i = 0; i < 256; ++i) all[i] = static_cast<uint8_t>(255 - i);
  for (int i = 0; i < 256; ++i) EXPECT_EQ(crc32_update(0x12345678U, &all[i], 1), bitwise(0x12345678U, &all[i], 1)) << i;
  EXPECT_EQ(crc32_update(0, all, 256), bitwise(0, all, 256));
  EXPECT_EQ(crc32_update(crc32_update(0, all, 100), all + 100, 156), crc32_update(0, all, 256));
}

TEST(Crc32, KnownCheckValue) {
  const uint8_t data[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc32_update(0, data, 9), 0xCBF43926U);
}

}  // namespace
}  // namespace uwbnav
