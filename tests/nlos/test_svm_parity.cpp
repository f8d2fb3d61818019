// Protects the embedded SVM evaluator: bit-compatible scaling and decision with
// libsvm, probability equal to libsvm 3.24 svm_predict_probability to 1e-5,
// checksum verification, and the committed default models' integrity.
#include <svm.h>

#include <cmath>
#include <random>
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
    svm_scale(tp.embedded, train[i].features, x);
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

TEST(SvmParity, EmbeddedProbabilityMatchesLibsvmPredictProbabilityTo1e5) {
  const auto train = make_samples(300, 7);
  const auto test = make_samples(2000, 99);
  TrainedPair tp = train_pair(train, 4.0, 2.0);
  ASSERT_NE(tp.libsvm, nullptr);
  ASSERT_EQ(svm_get_nr_sv(tp.libsvm), tp.embedded.num_sv);
  ASSERT_DOUBLE_EQ(tp.libsvm->rho[0], tp.embedded.rho);
  ASSERT_DOUBLE_EQ(tp.libsvm->sv_coef[0][0], tp.embedded.coef[0]);
  ASSERT_DOUBLE_EQ(tp.libsvm->SV[0][0].value, tp.embedded.sv[0][0]);
  ASSERT_DOUBLE_EQ(tp.libsvm->SV[0][1].value, tp.embedded.sv[0][1]);
  int labels[2];
  svm_get_labels(tp.libsvm, labels);
  double max_diff = 0.0;
  size_t near_half = 0;
  for (const auto& s : test) {
    double x[kSvmMaxFeatures] = {};
    svm_scale(tp.embedded, s.features, x);
    svm_node nodes[3] = {{1, x[0]}, {2, x[1]}, {-1, 0.0}};
    double pe[2] = {0.0, 0.0};
    svm_predict_probability(tp.libsvm, nodes, pe);
    const double p_lib = labels[0] == 1 ? pe[0] : pe[1];
    const Result<float> p = svm_nlos_probability(tp.embedded, s.features);
    ASSERT_TRUE(p.ok());
    max_diff = std::fmax(max_diff, std::fabs(static_cast<double>(p.value()) - p_lib));
    if (std::fabs(p_lib - 0.5) < 0.01) ++near_half;
    double dec = 0.0;
    svm_predict_values(tp.libsvm, nodes, &dec);
    EXPECT_NEAR(svm_decision_value(tp.embedded, x), dec, 1e-9);
  }
  EXPECT_LT(max_diff, 1e-5);
  svm_free_and_destroy_model(&tp.libsvm);
}

TEST(SvmParity, TwoClassProbabilityIsClippedSigmoidWithoutCoupling) {
  // libsvm 3.24 returns the Platt sigmoid for two classes; the multi-class coupling
  // iteration would stop at exactly 0.5 here (its tolerance is 0.0025).
  SvmModel m;
  m.prob_a = -1.0;
  m.prob_b = 0.0;
  EXPECT_DOUBLE_EQ(svm_label0_probability(m, 0.01), 1.0 / (1.0 + std::exp(-0.01)));
  EXPECT_DOUBLE_EQ(svm_label0_probability(m, 40.0), 1.0 - 1e-7);
  EXPECT_DOUBLE_EQ(svm_label0_probability(m, -40.0), 1e-7);
}

TEST(SvmModelChecksum, CorruptedCoefficientIsDetected) {
  const auto train = make_samples(200, 3);
  TrainedPair tp = train_pair(train, 2.0, 1.0);
  svm_free_and_destroy_model(&tp.libsvm);
  ASSERT_TRUE(ok(svm_model_validate(tp.embedded)));
  SvmModel bad = tp.embedded;
  bad.coef[0] += 1e-9;
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

TEST(Crc32, KnownCheckValue) {
  const uint8_t data[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc32_update(0, data, 9), 0xCBF43926U);
}

}  // namespace
}  // namespace uwbnav
