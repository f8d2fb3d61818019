// Protects the host-side NLOS tools: the edited training recipe respects the
// support-vector capacity and stays calibrated, the generated source carries the
// checksum, feature tables are read with position groups (hanyang), recordings
// yield eq. 1 range rates, and the Table-2 metrics follow seed 000 eq. 11-13.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "tools/eval/eval_nlos.hpp"
#include "tools/eval/svm_features.hpp"
#include "tools/eval/svm_train.hpp"

namespace uwbnav {
namespace {

std::vector<eval::SvmSample> overlapping_classes(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0F, 1.0F);
  std::vector<eval::SvmSample> out;
  for (size_t i = 0; i < n; ++i) {
    eval::SvmSample s;
    s.label = static_cast<int>(i % 2);
    s.features[0] = (s.label != 0 ? 12.0F : 0.0F) + 8.0F * noise(rng);
    s.features[1] = 5.0F + 2.0F * noise(rng);
    out.push_back(s);
  }
  return out;
}

TEST(SvmTraining, EditedRecipeFitsCapacityAndIsCalibrated) {
  const auto samples = overlapping_classes(6000, 5);
  eval::SvmTrainOptions opt;
  opt.set = SvmFeatureSet::kRangeRateSpeed;
  opt.capacity = 64;
  opt.edit_pool = 2000;
  opt.validation_samples = 2000;
  opt.max_train_samples = 1500;
  opt.c_grid = {1.0, 16.0};
  opt.gamma_grid = {0.5, 4.0};
  SvmModel model;
  eval::SvmTrainReport report;
  std::string err;
  ASSERT_TRUE(ok(eval::train_svm_model(samples, opt, model, report, &err))) << err;
  EXPECT_LE(model.num_sv, 64U);
  EXPECT_TRUE(ok(svm_model_validate(model)));
  EXPECT_GT(report.best_cv_accuracy, 0.7);
  // Calibration on unseen samples: mean p1 close to the NLOS frequency in p1 bins.
  const auto test = overlapping_classes(4000, 77);
  double sum_p_hi = 0.0, n_hi = 0.0, pos_hi = 0.0;
  for (const auto& s : test) {
    const Result<float> p = svm_nlos_probability(model, s.features);
    ASSERT_TRUE(p.ok());
    if (p.value() > 0.7F) {
      sum_p_hi += static_cast<double>(p.value());
      n_hi += 1.0;
      pos_hi += s.label;
    }
  }
  ASSERT_GT(n_hi, 100.0);
  EXPECT_NEAR(sum_p_hi / n_hi, pos_hi / n_hi, 0.08);
}

TEST(SvmTraining, DefaultRecipeShrinksTrainingSetToCapacity) {
  const auto samples = overlapping_classes(3000, 9);
  eval::SvmTrainOptions opt;
  opt.set = SvmFeatureSet::kRangeRateSpeed;
  opt.capacity = 48;
  opt.grid_samples = 400;
  opt.c_grid = {4.0};
  opt.gamma_grid = {1.0};
  SvmModel model;
  eval::SvmTrainReport report;
  std::string err;
  ASSERT_TRUE(ok(eval::train_svm_model(samples, opt, model, report, &err))) << err;
  EXPECT_LE(model.num_sv, 48U);
  EXPECT_LT(report.samples_trained, 3000U);
}

TEST(SvmExport, GeneratedSourceCarriesNameAndChecksum) {
  const auto samples = overlapping_classes(400, 3);
  eval::SvmTrainOptions opt;
  opt.c_grid = {2.0};
  opt.gamma_grid = {1.0};
  SvmModel model;
  eval::SvmTrainReport report;
  std::string err;
  ASSERT_TRUE(ok(eval::train_svm_model(samples, opt, model, report, &err))) << err;
  const std::string src = eval::export_models_cpp({model}, {"kSvmModelTest"}, {report}, "uwbnav train-svm test");
  char crc[16];
  std::snprintf(crc, sizeof(crc), "0x%08X", static_cast<unsigned>(model.crc32));
  EXPECT_NE(src.find("do not edit"), std::string::npos);
  EXPECT_NE(src.find("const SvmModel kSvmModelTest = {"), std::string::npos);
  EXPECT_NE(src.find(crc), std::string::npos);
}

TEST(SvmFeatures, HanyangTableReadWithPositionGroups) {
  // Shipped gzip-compressed (data/hanyang/hanyang_static_nlos_features.csv.gz); the reader finds the .gz.
  const std::string path = std::string(UWBNAV_DATA_DIR) + "/hanyang/hanyang_static_nlos_features.csv";
  std::vector<eval::SvmSample> samples;
  std::string err;
  ASSERT_TRUE(ok(eval::samples_from_table(path, SvmFeatureSet::kChannel, samples, &err))) << err;
  EXPECT_EQ(samples.size(), 36254U);  // one row lacks rx power
  int max_group = 0;
  for (const auto& s : samples) max_group = std::max(max_group, s.group);
  EXPECT_GT(max_group, 100);  // heights x distances
  EXPECT_NEAR(samples[0].features[0], -78.63F - -80.77F, 1e-4F);
}

TEST(SvmFeatures, RecordingRangeRateIsEq1) {
  dataset::Recording rec;
  for (int k = 0; k < 3; ++k) {
    dataset::UwbRow row;
    row.range.t_us = 100000U * static_cast<uint64_t>(k);
    row.range.anchor_id = 7;
    row.range.range_m = 10.0F + 0.5F * static_cast<float>(k * k);
    row.nlos_label = k == 2 ? 1 : 0;
    rec.uwb.push_back(row);
  }
  std::vector<eval::SvmSample> out;
  std::string err;
  ASSERT_TRUE(ok(eval::samples_from_recording(rec, SvmFeatureSet::kRangeRate, 500000, out, &err))) << err;
  ASSERT_EQ(out.size(), 2U);  // the first range has no predecessor
  EXPECT_NEAR(out[0].features[0], 5.0F, 1e-4F);   // 0.5 m in 0.1 s
  EXPECT_NEAR(out[1].features[0], 15.0F, 1e-4F);  // 1.5 m in 0.1 s
  EXPECT_EQ(out[1].label, 1);
}

TEST(NlosMetrics, PrecisionRecallAccuracyEq11To13) {
  eval::Confusion c;
  for (int i = 0; i < 8; ++i) c.add(true, true);    // TP
  for (int i = 0; i < 2; ++i) c.add(false, true);   // FP
  for (int i = 0; i < 6; ++i) c.add(false, false);  // TN
  for (int i = 0; i < 4; ++i) c.add(true, false);   // FN
  EXPECT_DOUBLE_EQ(c.precision(), 0.8);
  EXPECT_DOUBLE_EQ(c.recall(), 8.0 / 12.0);
  EXPECT_DOUBLE_EQ(c.accuracy(), 0.7);
  EXPECT_TRUE(std::isnan(eval::Confusion{}.precision()));
}

}  // namespace
}  // namespace uwbnav
