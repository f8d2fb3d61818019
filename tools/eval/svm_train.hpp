// Offline SVM training for NLOS identification (seed 000 §1.2(1)): svm-scale
// scaling, C/gamma grid search by k-fold cross-validation, libsvm C-SVC with
// RBF kernel and Platt probabilities, support-vector capacity of the embedded
// evaluator, export as generated C++ source (`uwbnav train-svm`).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/nlos/svm_model.hpp"
#include "estimator/status.hpp"
#include "tools/eval/svm_features.hpp"

namespace uwbnav::eval {

struct SvmTrainOptions {
  SvmFeatureSet set = SvmFeatureSet::kRangeRateSpeed;
  int folds = 5;                   // k of the cross-validation
  bool grouped_cv = false;         // folds hold out whole groups (SvmSample::group)
  std::vector<double> c_grid;      // empty: 2^-1, 2^1, ..., 2^9
  std::vector<double> gamma_grid;  // empty: 2^-3, 2^-1, ..., 2^5
  size_t grid_samples = 2000;      // minimum cross-validation set of the grid search
  size_t max_train_samples = 3000; // largest training set tried (per grid point and final)
  size_t capacity = kSvmMaxSupportVectors;  // nSV limit of the embedded evaluator
  uint64_t seed = 1;               // subsampling and libsvm's rand() (Platt CV, folds)
  bool verbose = false;            // grid progress on stderr
  size_t edit_pool = 0;            // > 0: Wilson-edited recipe on a pool of this many samples
  size_t validation_samples = 8000;  // edited recipe: unedited validation set size
};

struct SvmGridPoint {
  double c = 0.0;
  double gamma = 0.0;
  double cv_accuracy = 0.0;  // [0,1]
  size_t train_size = 0;     // largest training set whose model fits the capacity
};

struct SvmTrainReport {
  std::vector<SvmGridPoint> grid;
  double best_c = 0.0;
  double best_gamma = 0.0;
  double best_cv_accuracy = 0.0;  // of the grid search [0,1] (validation accuracy when edited)
  size_t samples_edited = 0;      // edited recipe: pool size after editing
  size_t samples_available = 0;
  size_t samples_trained = 0;     // final training set size (after the capacity rule)
  size_t num_sv = 0;
  int capacity_retries = 0;       // retrains with a smaller training set
};

// svm-scale scaling in double (host, training and libsvm reference): the libsvm
// problem is built from these values; the embedded svm_scale computes it in float.
void svm_scale_double(const SvmModel& scaling, const float* raw, double* scaled);

// Scaling (min/max of `train` -> [-1, 1]) into a model (only scale_min/max/num_features/feature_set set).
void fit_scaling(const std::vector<SvmSample>& train, SvmFeatureSet set, SvmModel& scaling);

// Fold (0..folds-1) of each sample, deterministic in `seed`. Random folds are
// stratified by label. Grouped folds keep each SvmSample::group whole and are
// class-stratified: groups holding one class only are spread first so that
// every fold holds out both classes where the groups allow it. kInvalidArgument
// (and `error` naming the fold, e.g. "fold 4 of 5 would hold out no NLOS
// sample", with the group counts) when a fold would still hold out, or train
// on, one class only.
[[nodiscard]] Status assign_folds(const std::vector<SvmSample>& samples, int folds, bool grouped, uint64_t seed,
                                  std::vector<int>& fold, std::string* error);

// k-fold cross-validated predictions (label per sample, probability of NLOS when
// `probability`) for fixed C, gamma; scaling fitted on each training fold.
// Refuses (assign_folds' status and error) when a fold would hold one class only.
[[nodiscard]] Status cross_validate(const std::vector<SvmSample>& samples, SvmFeatureSet set, double c, double gamma,
                                    int folds, bool grouped, bool probability, uint64_t seed,
                                    std::vector<int>* predicted, std::vector<double>* p_nlos,
                                    std::string* error = nullptr);

// Trains one model under the support-vector capacity of the embedded evaluator.
// Capacity rule: training sets are stratified subsamples of at most
// max_train_samples; while a model has nSV > capacity its set shrinks to
// 0.9 * n * capacity / nSV and it is retrained. The grid search applies the rule
// per (C, gamma) and cross-validates on folds of the resulting size; the final
// model (probability = 1) uses the winner's size. With edit_pool > 0 the edited
// recipe is used instead (Wilson editing, validation-set selection, Platt refit).
[[nodiscard]] Status train_svm_model(const std::vector<SvmSample>& samples, const SvmTrainOptions& options,
                                     SvmModel& model, SvmTrainReport& report, std::string* error);

// Generated C++ source defining `const SvmModel <names[i]>` for each model.
std::string export_models_cpp(const std::vector<SvmModel>& models, const std::vector<std::string>& names,
                              const std::vector<SvmTrainReport>& reports, const std::string& command_line);

// Stratified subsample of at most n samples (all when fewer), deterministic in seed.
std::vector<SvmSample> stratified_subsample(const std::vector<SvmSample>& samples, size_t n, uint64_t seed);

// `uwbnav train-svm ...` (argv[0] is the command name). Exit code 0 on success.
int run_train_svm(int argc, char** argv);

}  // namespace uwbnav::eval
