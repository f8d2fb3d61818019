// Offline SVM training with libsvm and export of the embedded models (`uwbnav train-svm`).
#include "tools/eval/svm_train.hpp"

#include <svm.h>

#include <algorithm>
#include <array>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>

#include "tools/sim/simulator.hpp"

namespace uwbnav::eval {

namespace {

void quiet_print(const char*) {}

// A libsvm problem owning its nodes.
struct Problem {
  std::vector<svm_node> nodes;
  std::vector<svm_node*> rows;
  std::vector<double> labels;
  svm_problem prob{};
};

void scale_sample(const SvmModel& scaling, const SvmSample& s, double* out) {
  svm_scale_double(scaling, s.features, out);
}

std::unique_ptr<Problem> make_problem(const std::vector<SvmSample>& samples, const SvmModel& scaling) {
  auto p = std::make_unique<Problem>();
  const size_t nf = scaling.num_features;
  p->nodes.resize(samples.size() * (nf + 1));
  p->rows.resize(samples.size());
  p->labels.resize(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    double x[kSvmMaxFeatures] = {};
    scale_sample(scaling, samples[i], x);
    svm_node* row = &p->nodes[i * (nf + 1)];
    for (size_t f = 0; f < nf; ++f) {
      row[f].index = static_cast<int>(f + 1);
      row[f].value = x[f];
    }
    row[nf].index = -1;
    row[nf].value = 0.0;
    p->rows[i] = row;
    p->labels[i] = samples[i].label;
  }
  p->prob.l = static_cast<int>(samples.size());
  p->prob.y = p->labels.data();
  p->prob.x = p->rows.data();
  return p;
}

svm_parameter make_param(double c, double gamma, bool probability) {
  svm_parameter param{};
  param.svm_type = C_SVC;
  param.kernel_type = RBF;
  param.gamma = gamma;
  param.C = c;
  param.cache_size = 200;
  param.eps = 1e-3;
  param.shrinking = 1;
  param.probability = probability ? 1 : 0;
  param.nr_weight = 0;
  return param;
}

// libsvm model -> embedded model (scaling copied from `scaling`): the double model
// rounded to float (round to nearest), support vectors stored feature-major.
bool to_embedded(const svm_model* lm, const SvmModel& scaling, size_t capacity, SvmModel& out) {
  if (svm_get_nr_class(lm) != 2 || svm_check_probability_model(lm) == 0) return false;
  const int nsv = svm_get_nr_sv(lm);
  if (nsv <= 0 || static_cast<size_t>(nsv) > capacity || static_cast<size_t>(nsv) > kSvmMaxSupportVectors) {
    return false;
  }
  out = SvmModel{};
  out.version = kSvmModelVersion;
  out.feature_set = scaling.feature_set;
  out.num_features = scaling.num_features;
  out.num_sv = static_cast<uint16_t>(nsv);
  int labels[2] = {0, 0};
  svm_get_labels(lm, labels);
  out.first_label_nlos = labels[0] == 1 ? 1 : 0;
  out.gamma = static_cast<float>(lm->param.gamma);
  out.rho = static_cast<float>(lm->rho[0]);
  out.prob_a = static_cast<float>(lm->probA[0]);
  out.prob_b = static_cast<float>(lm->probB[0]);
  for (size_t f = 0; f < kSvmMaxFeatures; ++f) {
    out.scale_min[f] = scaling.scale_min[f];
    out.scale_max[f] = scaling.scale_max[f];
  }
  for (int i = 0; i < nsv; ++i) {
    for (const svm_node* n = lm->SV[i]; n->index != -1; ++n) {
      if (n->index >= 1 && static_cast<size_t>(n->index) <= out.num_features) {
        out.sv[n->index - 1][i] = static_cast<float>(n->value);
      }
    }
    out.coef[i] = static_cast<float>(lm->sv_coef[0][i]);
  }
  out.crc32 = svm_model_crc32(out);
  return true;
}

std::vector<double> default_grid(int lo_exp, int hi_exp, int step) {
  std::vector<double> g;
  for (int e = lo_exp; e <= hi_exp; e += step) g.push_back(std::ldexp(1.0, e));
  return g;
}

std::string format_float(float v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", static_cast<double>(v));
  std::string s = buf;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s + "F";
}

}  // namespace

namespace {

// Largest stratified training subsample (at most max_train_samples) whose C-SVC model
// for (c, g) has at most `capacity` support vectors; 0 when none is found.
size_t feasible_size(const std::vector<SvmSample>& samples, const SvmTrainOptions& options, double c, double g) {
  size_t n = std::min(samples.size(), options.max_train_samples);
  for (int attempt = 0; attempt < 12 && n >= 20; ++attempt) {
    const std::vector<SvmSample> train = stratified_subsample(samples, n, options.seed + 17U);
    SvmModel scaling;
    fit_scaling(train, options.set, scaling);
    auto prob = make_problem(train, scaling);
    const svm_parameter param = make_param(c, g, false);
    svm_model* lm = svm_train(&prob->prob, &param);
    const size_t nsv = static_cast<size_t>(svm_get_nr_sv(lm));
    svm_free_and_destroy_model(&lm);
    if (nsv <= options.capacity) return train.size();
    n = static_cast<size_t>(0.9 * static_cast<double>(train.size()) * static_cast<double>(options.capacity) /
                            static_cast<double>(nsv));
  }
  return 0;
}

// Wilson editing: keeps the samples whose label agrees with the majority of their k
// nearest neighbours (scaled feature space). Removes the overlap of the classes so that
// a capacity-limited SVM spends its support vectors on the decision boundary.
std::vector<SvmSample> wilson_edit(const std::vector<SvmSample>& pool, SvmFeatureSet set, size_t k) {
  SvmModel scaling;
  fit_scaling(pool, set, scaling);
  const size_t nf = scaling.num_features;
  std::vector<double> x(pool.size() * nf);
  for (size_t i = 0; i < pool.size(); ++i) svm_scale_double(scaling, pool[i].features, &x[i * nf]);
  std::vector<SvmSample> kept;
  std::vector<std::pair<double, int>> d(pool.size());
  for (size_t i = 0; i < pool.size(); ++i) {
    for (size_t j = 0; j < pool.size(); ++j) {
      double s2 = 0.0;
      for (size_t f = 0; f < nf; ++f) {
        const double df = x[i * nf + f] - x[j * nf + f];
        s2 += df * df;
      }
      d[j] = {i == j ? 1e300 : s2, pool[j].label};
    }
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
    size_t agree = 0;
    for (size_t m = 0; m < k; ++m) agree += d[m].second == pool[i].label ? 1U : 0U;
    if (2 * agree > k) kept.push_back(pool[i]);
  }
  return kept;
}

// Platt scaling fitted on decision values (Platt 1999 with the Newton/backtracking
// method of Lin, Lin and Weng 2007): P(label0 | f) = 1 / (1 + exp(A f + B)).
void fit_platt(const std::vector<double>& dec, const std::vector<int>& is_label0, double* a_out, double* b_out) {
  double prior1 = 0.0;
  double prior0 = 0.0;
  for (int y : is_label0) (y != 0 ? prior1 : prior0) += 1.0;
  const double hi = (prior1 + 1.0) / (prior1 + 2.0);
  const double lo = 1.0 / (prior0 + 2.0);
  std::vector<double> t(dec.size());
  for (size_t i = 0; i < dec.size(); ++i) t[i] = is_label0[i] != 0 ? hi : lo;
  auto objective = [&](double a, double b) {
    double f = 0.0;
    for (size_t i = 0; i < dec.size(); ++i) {
      const double z = dec[i] * a + b;
      f += z >= 0.0 ? t[i] * z + std::log1p(std::exp(-z)) : (t[i] - 1.0) * z + std::log1p(std::exp(z));
    }
    return f;
  };
  double a = 0.0;
  double b = std::log((prior0 + 1.0) / (prior1 + 1.0));
  double fval = objective(a, b);
  for (int iter = 0; iter < 100; ++iter) {
    double h11 = 1e-12, h22 = 1e-12, h21 = 0.0, g1 = 0.0, g2 = 0.0;
    for (size_t i = 0; i < dec.size(); ++i) {
      const double z = dec[i] * a + b;
      double p = 0.0;
      double q = 0.0;
      if (z >= 0.0) {
        p = std::exp(-z) / (1.0 + std::exp(-z));
        q = 1.0 / (1.0 + std::exp(-z));
      } else {
        p = 1.0 / (1.0 + std::exp(z));
        q = std::exp(z) / (1.0 + std::exp(z));
      }
      const double d2 = p * q;
      h11 += dec[i] * dec[i] * d2;
      h22 += d2;
      h21 += dec[i] * d2;
      const double d1 = t[i] - p;
      g1 += dec[i] * d1;
      g2 += d1;
    }
    if (std::fabs(g1) < 1e-5 && std::fabs(g2) < 1e-5) break;
    const double det = h11 * h22 - h21 * h21;
    const double da = -(h22 * g1 - h21 * g2) / det;
    const double db = -(-h21 * g1 + h11 * g2) / det;
    const double gd = g1 * da + g2 * db;
    double step = 1.0;
    bool moved = false;
    while (step >= 1e-10) {
      const double fa = a + step * da;
      const double fb = b + step * db;
      const double nf = objective(fa, fb);
      if (nf < fval + 1e-4 * step * gd) {
        a = fa;
        b = fb;
        fval = nf;
        moved = true;
        break;
      }
      step *= 0.5;
    }
    if (!moved) break;
  }
  *a_out = a;
  *b_out = b;
}

// Accuracy of a libsvm model on samples (scaled with `scaling`); decision values out.
double validate(const svm_model* lm, const SvmModel& scaling, const std::vector<SvmSample>& val,
                std::vector<double>* dec_out) {
  size_t correct = 0;
  if (dec_out != nullptr) dec_out->assign(val.size(), 0.0);
  for (size_t i = 0; i < val.size(); ++i) {
    double x[kSvmMaxFeatures] = {};
    svm_scale_double(scaling, val[i].features, x);
    svm_node nodes[kSvmMaxFeatures + 1];
    for (size_t f = 0; f < scaling.num_features; ++f) nodes[f] = svm_node{static_cast<int>(f + 1), x[f]};
    nodes[scaling.num_features].index = -1;
    double dec = 0.0;
    const double label = svm_predict_values(lm, nodes, &dec);
    if (dec_out != nullptr) (*dec_out)[i] = dec;
    correct += (label > 0.5 ? 1 : 0) == val[i].label ? 1U : 0U;
  }
  return val.empty() ? 0.0 : static_cast<double>(correct) / static_cast<double>(val.size());
}

}  // namespace

std::vector<SvmSample> stratified_subsample(const std::vector<SvmSample>& samples, size_t n, uint64_t seed) {
  if (samples.size() <= n) return samples;
  std::mt19937_64 rng(seed);
  std::vector<size_t> by_label[2];
  for (size_t i = 0; i < samples.size(); ++i) by_label[samples[i].label != 0 ? 1 : 0].push_back(i);
  std::vector<size_t> keep;
  for (auto& idx : by_label) {
    std::shuffle(idx.begin(), idx.end(), rng);
    const size_t k = static_cast<size_t>(std::llround(static_cast<double>(n) * static_cast<double>(idx.size()) /
                                                      static_cast<double>(samples.size())));
    keep.insert(keep.end(), idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(std::min(k, idx.size())));
  }
  std::sort(keep.begin(), keep.end());
  std::vector<SvmSample> out;
  out.reserve(keep.size());
  for (size_t i : keep) out.push_back(samples[i]);
  return out;
}

void svm_scale_double(const SvmModel& scaling, const float* raw, double* scaled) {
  for (size_t f = 0; f < scaling.num_features; ++f) {
    const double lo = static_cast<double>(scaling.scale_min[f]);
    const double hi = static_cast<double>(scaling.scale_max[f]);
    // svm-scale: lower + (upper - lower) * (x - min) / (max - min), lower -1, upper +1.
    scaled[f] = hi <= lo ? 0.0 : -1.0 + 2.0 * (static_cast<double>(raw[f]) - lo) / (hi - lo);
  }
}

void fit_scaling(const std::vector<SvmSample>& train, SvmFeatureSet set, SvmModel& scaling) {
  scaling = SvmModel{};
  scaling.feature_set = static_cast<uint8_t>(set);
  scaling.num_features = static_cast<uint8_t>(svm_feature_count(set));
  for (size_t f = 0; f < scaling.num_features; ++f) {
    float lo = 0.0F;
    float hi = 0.0F;
    bool first = true;
    for (const auto& s : train) {
      if (first || s.features[f] < lo) lo = s.features[f];
      if (first || s.features[f] > hi) hi = s.features[f];
      first = false;
    }
    scaling.scale_min[f] = lo;
    scaling.scale_max[f] = hi;
  }
}

namespace {

const char* class_name(int label) { return label != 0 ? "NLOS" : "LOS"; }

// Whole groups to folds, class-stratified: groups are taken NLOS-only first,
// then LOS-only, then mixed (each kind in seeded random order); each goes to
// the fold that still lacks a class the group brings, else to the fold with
// the fewest samples (lowest index on ties).
void assign_grouped(const std::vector<SvmSample>& samples, int folds, std::mt19937_64& rng, std::vector<int>& fold) {
  std::map<int, std::array<size_t, 2>> count;  // group -> samples per label
  for (const auto& s : samples) ++count[s.group][s.label != 0 ? 1 : 0];
  std::vector<int> kinds[3];  // 0: NLOS-only, 1: LOS-only, 2: mixed
  for (const auto& [g, n] : count) kinds[n[0] == 0 ? 0 : (n[1] == 0 ? 1 : 2)].push_back(g);
  const size_t k = static_cast<size_t>(folds);
  std::vector<std::array<bool, 2>> has(k, {false, false});
  std::vector<size_t> size(k, 0);
  std::map<int, int> group_fold;
  for (auto& list : kinds) {
    std::shuffle(list.begin(), list.end(), rng);
    for (int g : list) {
      const auto& n = count[g];
      size_t best = 0;
      bool best_fills = false;
      for (size_t f = 0; f < k; ++f) {
        const bool fills = (n[0] > 0 && !has[f][0]) || (n[1] > 0 && !has[f][1]);
        if (f == 0 || (fills && !best_fills) || (fills == best_fills && size[f] < size[best])) {
          best = f;
          best_fills = fills;
        }
      }
      group_fold[g] = static_cast<int>(best);
      has[best][0] = has[best][0] || n[0] > 0;
      has[best][1] = has[best][1] || n[1] > 0;
      size[best] += n[0] + n[1];
    }
  }
  for (size_t i = 0; i < samples.size(); ++i) fold[i] = group_fold[samples[i].group];
}

}  // namespace

Status assign_folds(const std::vector<SvmSample>& samples, int folds, bool grouped, uint64_t seed,
                    std::vector<int>& fold, std::string* error) {
  fold.assign(samples.size(), 0);
  if (folds < 2) {
    if (error != nullptr) *error = "cross-validation needs at least 2 folds, got " + std::to_string(folds);
    return Status::kInvalidArgument;
  }
  std::mt19937_64 rng(seed);
  if (grouped) {
    assign_grouped(samples, folds, rng, fold);
  } else {
    for (int label = 0; label <= 1; ++label) {
      std::vector<size_t> idx;
      for (size_t i = 0; i < samples.size(); ++i) {
        if (samples[i].label == label) idx.push_back(i);
      }
      std::shuffle(idx.begin(), idx.end(), rng);
      for (size_t k = 0; k < idx.size(); ++k) fold[idx[k]] = static_cast<int>(k % static_cast<size_t>(folds));
    }
  }
  // Every fold must hold out both classes and train on both.
  std::vector<std::array<size_t, 2>> held(static_cast<size_t>(folds), {0, 0});
  std::array<size_t, 2> total = {0, 0};
  std::map<int, std::array<size_t, 2>> groups;
  for (size_t i = 0; i < samples.size(); ++i) {
    const int c = samples[i].label != 0 ? 1 : 0;
    ++held[static_cast<size_t>(fold[i])][static_cast<size_t>(c)];
    ++total[static_cast<size_t>(c)];
    ++groups[samples[i].group][static_cast<size_t>(c)];
  }
  for (int k = 0; k < folds; ++k) {
    const auto& h = held[static_cast<size_t>(k)];
    for (int c = 0; c <= 1; ++c) {
      const bool test_lacks = h[static_cast<size_t>(c)] == 0;
      const bool train_lacks = total[static_cast<size_t>(c)] == h[static_cast<size_t>(c)];
      if (!test_lacks && !train_lacks) continue;
      if (error != nullptr) {
        std::string why = std::string(grouped ? "grouped" : "stratified") + " cross-validation refused: fold " +
                          std::to_string(k + 1) + " of " + std::to_string(folds) + " would " +
                          (test_lacks ? std::string("hold out no ") + class_name(c) + " sample"
                                      : std::string("train on no ") + class_name(c) + " sample");
        if (grouped) {
          size_t only[2] = {0, 0};
          size_t mixed = 0;
          for (const auto& [g, n] : groups) {
            if (n[0] > 0 && n[1] > 0) {
              ++mixed;
            } else {
              ++only[n[1] > 0 ? 1 : 0];
            }
          }
          why += " (" + std::to_string(groups.size()) + " groups: " + std::to_string(only[1]) + " NLOS-only, " +
                 std::to_string(only[0]) + " LOS-only, " + std::to_string(mixed) +
                 " mixed; every fold needs a group with each class: use fewer folds or random folds)";
        } else {
          why += " (" + std::to_string(total[1]) + " NLOS, " + std::to_string(total[0]) + " LOS samples)";
        }
        *error = why;
      }
      return Status::kInvalidArgument;
    }
  }
  return Status::kOk;
}

Status cross_validate(const std::vector<SvmSample>& samples, SvmFeatureSet set, double c, double gamma, int folds,
                    bool grouped, bool probability, uint64_t seed, std::vector<int>* predicted,
                      std::vector<double>* p_nlos, std::string* error) {
  svm_set_print_string_function(quiet_print);
  if (predicted != nullptr) predicted->assign(samples.size(), 0);
  if (p_nlos != nullptr) p_nlos->assign(samples.size(), std::nan(""));
  std::vector<int> fold;
  const Status fs = assign_folds(samples, folds, grouped, seed, fold, error);
  if (!ok(fs)) return fs;
  for (int k = 0; k < folds; ++k) {
    std::vector<SvmSample> train;
    std::vector<size_t> test;
    for (size_t i = 0; i < samples.size(); ++i) {
      if (fold[i] == k) {
        test.push_back(i);
      } else {
        train.push_back(samples[i]);
      }
    }
    if (train.empty() || test.empty()) continue;
    SvmModel scaling;
    fit_scaling(train, set, scaling);
    auto prob = make_problem(train, scaling);
    const svm_parameter param = make_param(c, gamma, probability);
    std::srand(static_cast<unsigned>(seed + static_cast<uint64_t>(k)));
    svm_model* lm = svm_train(&prob->prob, &param);
    int labels[2] = {0, 0};
    svm_get_labels(lm, labels);
    for (size_t i : test) {
      double x[kSvmMaxFeatures] = {};
      scale_sample(scaling, samples[i], x);
      svm_node nodes[kSvmMaxFeatures + 1];
      for (size_t f = 0; f < scaling.num_features; ++f) {
        nodes[f].index = static_cast<int>(f + 1);
        nodes[f].value = x[f];
      }
      nodes[scaling.num_features].index = -1;
      double label = 0.0;
      if (probability && svm_check_probability_model(lm) != 0) {
        double pe[2] = {0.0, 0.0};
        label = svm_predict_probability(lm, nodes, pe);
        if (p_nlos != nullptr) (*p_nlos)[i] = labels[0] == 1 ? pe[0] : pe[1];
      } else {
        label = svm_predict(lm, nodes);
      }
      if (predicted != nullptr) (*predicted)[i] = label > 0.5 ? 1 : 0;
    }
    svm_free_and_destroy_model(&lm);
  }
  return Status::kOk;
}

// Keeps one grid point of the C/gamma search in the report and tracks the best
// (strictly better accuracy wins, so ties keep the earlier, smaller C/gamma).
static void record_grid_point(const SvmGridPoint& gp, const char* score_name, bool verbose, SvmTrainReport& report,
                              size_t& best_n) {
  report.grid.push_back(gp);
  if (verbose) {
    std::fprintf(stderr, "  C=%-8g gamma=%-8g n=%-5zu %s=%.4f\n", gp.c, gp.gamma, gp.train_size, score_name,
                 gp.cv_accuracy);
  }
  if (gp.cv_accuracy > report.best_cv_accuracy + 1e-12) {
    report.best_cv_accuracy = gp.cv_accuracy;
    report.best_c = gp.c;
    report.best_gamma = gp.gamma;
    best_n = gp.train_size;
  }
}

namespace {

// The edited recipe (options.edit_pool > 0): Wilson-edited training pool, (C, gamma)
// chosen by accuracy on a disjoint unedited validation set under the capacity rule,
// Platt parameters refitted on that validation set (the edited data would make
// libsvm's internal Platt fit overconfident).
Status train_edited(const std::vector<SvmSample>& samples, const SvmTrainOptions& options,
                    const std::vector<double>& c_grid, const std::vector<double>& g_grid, SvmModel& model,
                    SvmTrainReport& report, std::string* error) {
  std::vector<size_t> order(samples.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::mt19937_64 rng(options.seed + 29U);
  std::shuffle(order.begin(), order.end(), rng);
  const size_t n_pool = std::min(options.edit_pool, samples.size() / 2);
  const size_t n_val = std::min(options.validation_samples, samples.size() - n_pool);
  std::vector<SvmSample> pool;
  std::vector<SvmSample> val;
  for (size_t i = 0; i < n_pool; ++i) pool.push_back(samples[order[i]]);
  for (size_t i = n_pool; i < n_pool + n_val; ++i) val.push_back(samples[order[i]]);
  const std::vector<SvmSample> edited = wilson_edit(pool, options.set, 15);
  report.samples_edited = edited.size();
  size_t best_n = 0;
  for (double c : c_grid) {
    for (double g : g_grid) {
      const size_t n_fit = feasible_size(edited, options, c, g);
      if (n_fit == 0) continue;
      const std::vector<SvmSample> train = stratified_subsample(edited, n_fit, options.seed + 17U);
      SvmModel scaling;
      fit_scaling(train, options.set, scaling);
      auto prob = make_problem(train, scaling);
      const svm_parameter param = make_param(c, g, false);
      svm_model* lm = svm_train(&prob->prob, &param);
      SvmGridPoint gp{c, g, validate(lm, scaling, val, nullptr), n_fit};
      svm_free_and_destroy_model(&lm);
      record_grid_point(gp, "validation", options.verbose, report, best_n);
    }
  }
  if (best_n == 0) {
    if (error != nullptr) *error = "no grid point meets the support-vector capacity";
    return Status::kFull;
  }
  const std::vector<SvmSample> train = stratified_subsample(edited, best_n, options.seed + 17U);
  SvmModel scaling;
  fit_scaling(train, options.set, scaling);
  auto prob = make_problem(train, scaling);
  const svm_parameter param = make_param(report.best_c, report.best_gamma, true);
  std::srand(static_cast<unsigned>(options.seed));
  svm_model* lm = svm_train(&prob->prob, &param);
  report.num_sv = static_cast<size_t>(svm_get_nr_sv(lm));
  report.samples_trained = train.size();
  std::vector<double> dec;
  validate(lm, scaling, val, &dec);
  const bool fits = to_embedded(lm, scaling, options.capacity, model);
  svm_free_and_destroy_model(&lm);
  if (!fits) {
    if (error != nullptr) *error = "cannot meet the support-vector capacity";
    return Status::kFull;
  }
  std::vector<int> is_label0(val.size());
  for (size_t i = 0; i < val.size(); ++i) is_label0[i] = (val[i].label != 0) == (model.first_label_nlos != 0) ? 1 : 0;
  double prob_a = 0.0;
  double prob_b = 0.0;
  fit_platt(dec, is_label0, &prob_a, &prob_b);
  model.prob_a = static_cast<float>(prob_a);
  model.prob_b = static_cast<float>(prob_b);
  model.crc32 = svm_model_crc32(model);
  return Status::kOk;
}

}  // namespace

Status train_svm_model(const std::vector<SvmSample>& samples, const SvmTrainOptions& options, SvmModel& model,
                       SvmTrainReport& report, std::string* error) {
  svm_set_print_string_function(quiet_print);
  report = SvmTrainReport{};
  report.samples_available = samples.size();
  size_t n_pos = 0;
  for (const auto& s : samples) n_pos += s.label != 0 ? 1U : 0U;
  if (samples.size() < 20 || n_pos < 5 || samples.size() - n_pos < 5) {
    if (error != nullptr) *error = "too few labelled samples of both classes";
    return Status::kInvalidArgument;
  }
  const std::vector<double> c_grid = options.c_grid.empty() ? default_grid(-1, 9, 2) : options.c_grid;
  const std::vector<double> g_grid = options.gamma_grid.empty() ? default_grid(-3, 5, 2) : options.gamma_grid;
  if (options.edit_pool > 0) return train_edited(samples, options, c_grid, g_grid, model, report, error);
  size_t best_n = 0;

  // Grid search (seed 000: parameters by k-fold cross-validation), capacity-aware: for each
  // (C, gamma) the largest stratified training set whose model fits the capacity is found
  // first, then the cross-validation runs on folds of that size, so the score is the score
  // of a model the firmware can actually hold.
  for (double c : c_grid) {
    for (double g : g_grid) {
      const size_t n_fit = feasible_size(samples, options, c, g);
      if (n_fit == 0) continue;
      const size_t n_cv = std::min(samples.size(), std::max(options.grid_samples,
          static_cast<size_t>(static_cast<double>(n_fit) * options.folds / (options.folds - 1))));
      const std::vector<SvmSample> cv_set = stratified_subsample(samples, n_cv, options.seed);
      const std::vector<SvmSample> grid_set =
          n_cv > n_fit * options.folds / (options.folds - 1) + 1
              ? stratified_subsample(cv_set, n_fit * static_cast<size_t>(options.folds) /
                                                 static_cast<size_t>(options.folds - 1), options.seed + 3U)
              : cv_set;
      size_t correct = 0;
      if (options.grouped_cv) {
        std::vector<int> pred;
        const Status cs =
            cross_validate(grid_set, options.set, c, g, options.folds, true, false, options.seed, &pred, nullptr, error);
        if (!ok(cs)) return cs;
        for (size_t k = 0; k < grid_set.size(); ++k) correct += pred[k] == grid_set[k].label ? 1U : 0U;
      } else {
        SvmModel grid_scaling;
        fit_scaling(grid_set, options.set, grid_scaling);
        auto grid_prob = make_problem(grid_set, grid_scaling);
        const svm_parameter param = make_param(c, g, false);
        std::vector<double> target(grid_set.size(), 0.0);
        std::srand(static_cast<unsigned>(options.seed));
        svm_cross_validation(&grid_prob->prob, &param, options.folds, target.data());
        for (size_t k = 0; k < grid_set.size(); ++k) correct += (target[k] > 0.5 ? 1 : 0) == grid_set[k].label ? 1U : 0U;
      }
      SvmGridPoint gp{c, g, static_cast<double>(correct) / static_cast<double>(grid_set.size()), n_fit};
      record_grid_point(gp, "cv", options.verbose, report, best_n);
    }
  }
  if (best_n == 0) {
    if (error != nullptr) *error = "no grid point meets the support-vector capacity";
    return Status::kFull;
  }

  // Final model under the support-vector capacity: shrink the training set until nSV fits.
  size_t n_train = best_n;
  for (int attempt = 0; attempt < 12; ++attempt) {
    const std::vector<SvmSample> train = stratified_subsample(samples, n_train, options.seed + 17U);
    SvmModel scaling;
    fit_scaling(train, options.set, scaling);
    auto prob = make_problem(train, scaling);
    const svm_parameter param = make_param(report.best_c, report.best_gamma, true);
    std::srand(static_cast<unsigned>(options.seed));
    svm_model* lm = svm_train(&prob->prob, &param);
    const size_t nsv = static_cast<size_t>(svm_get_nr_sv(lm));
    const bool fits = to_embedded(lm, scaling, options.capacity, model);
    svm_free_and_destroy_model(&lm);
    report.num_sv = nsv;
    report.samples_trained = train.size();
    if (fits) return Status::kOk;
    ++report.capacity_retries;
    n_train = static_cast<size_t>(0.9 * static_cast<double>(train.size()) * static_cast<double>(options.capacity) /
                                  static_cast<double>(nsv));
    if (n_train < 20) break;
  }
  if (error != nullptr) *error = "cannot meet the support-vector capacity";
  return Status::kFull;
}

std::string export_models_cpp(const std::vector<SvmModel>& models, const std::vector<std::string>& names,
                              const std::vector<SvmTrainReport>& reports, const std::string& command_line) {
  std::ostringstream o;
  o << "// GENERATED by `uwbnav train-svm` (tools/eval/svm_train.cpp) — do not edit.\n";
  o << "// Committed default NLOS SVM models of the embedded evaluator (estimator/nlos/svm_model.hpp):\n";
  o << "// libsvm's double models rounded to float (SvmModel version " << kSvmModelVersion << ").\n";
  o << "// Command: " << command_line << "\n";
  for (size_t m = 0; m < models.size(); ++m) {
    const SvmTrainReport& r = reports[m];
    char line[256];
    std::snprintf(line, sizeof(line),
                  "// %s: %s, C=%g gamma=%g, %s accuracy %.4f, %zu of %zu samples trained%s, %zu SVs\n",
                  names[m].c_str(), feature_set_name(static_cast<SvmFeatureSet>(models[m].feature_set)), r.best_c,
                  r.best_gamma, r.samples_edited > 0 ? "validation" : "grid CV", r.best_cv_accuracy,
                  r.samples_trained, r.samples_available, r.samples_edited > 0 ? " (Wilson-edited pool)" : "",
                  r.num_sv);
    o << line;
  }
  o << "#include \"estimator/nlos/svm_model.hpp\"\n\nnamespace uwbnav {\n";
  for (size_t m = 0; m < models.size(); ++m) {
    const SvmModel& s = models[m];
    o << "\nconst SvmModel " << names[m] << " = {\n";
    o << "    " << s.version << "U,  // version\n";
    o << "    " << static_cast<int>(s.feature_set) << ",  // feature_set\n";
    o << "    " << static_cast<int>(s.num_features) << ",  // num_features\n";
    o << "    " << s.num_sv << ",  // num_sv\n";
    o << "    " << static_cast<int>(s.first_label_nlos) << ",  // first_label_nlos\n";
    o << "    " << format_float(s.gamma) << ",  // gamma\n";
    o << "    " << format_float(s.rho) << ",  // rho\n";
    o << "    " << format_float(s.prob_a) << ",  // prob_a\n";
    o << "    " << format_float(s.prob_b) << ",  // prob_b\n";
    o << "    {";
    for (size_t f = 0; f < s.num_features; ++f) o << (f ? ", " : "") << format_float(s.scale_min[f]);
    o << "},  // scale_min\n    {";
    for (size_t f = 0; f < s.num_features; ++f) o << (f ? ", " : "") << format_float(s.scale_max[f]);
    o << "},  // scale_max\n    {\n";
    for (size_t f = 0; f < s.num_features; ++f) {
      o << "        {  // sv feature " << f << "\n";
      for (size_t i = 0; i < s.num_sv; ++i) o << "            " << format_float(s.sv[f][i]) << ",\n";
      o << "        },\n";
    }
    o << "    },\n    {\n";
    for (size_t i = 0; i < s.num_sv; ++i) o << "        " << format_float(s.coef[i]) << ",\n";
    char crc[32];
    std::snprintf(crc, sizeof(crc), "0x%08" PRIX32 "U", s.crc32);
    o << "    },\n    " << crc << ",  // crc32\n};\n";
  }
  o << "\n}  // namespace uwbnav\n";
  return o.str();
}

namespace {

const char* model_name(SvmFeatureSet set) {
  switch (set) {
    case SvmFeatureSet::kRangeRate: return "kSvmModelRangeRate";
    case SvmFeatureSet::kRangeRateSpeed: return "kSvmModelRangeRateSpeed";
    case SvmFeatureSet::kChannel: return "kSvmModelChannel";
  }
  return "kSvmModel";
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream ss(s);
  while (std::getline(ss, cur, sep)) {
    if (!cur.empty()) out.push_back(cur);
  }
  return out;
}

int usage() {
  std::fprintf(stderr,
               "usage: uwbnav train-svm --features rr,rrs,channel\n"
               "         (--sim PRESET --seeds N[,N...] | --recording DIR | --table FILE.csv)...\n"
               "         [--out FILE.cpp] [--folds K] [--grouped] [--seed N] [--grid-samples N]\n"
               "         [--max-train N] [--capacity N] [--max-dt-us N] [--edit POOL] [--verbose]\n"
               "  rr: range rate (seed 000 SVM1); rrs: range rate + speed (SVM2); channel: rx-fp gap, fp power\n"
               "  --edit POOL: Wilson-edit a pool of POOL samples, select C/gamma and refit Platt on a\n"
               "  disjoint validation set (docs/nlos.md); default: k-fold CV on the raw samples\n");
  return 2;
}

}  // namespace

int run_train_svm(int argc, char** argv) {
  std::vector<std::string> feature_names;
  std::vector<std::string> sims;
  std::vector<uint64_t> seeds;
  std::vector<std::string> recordings;
  std::vector<std::string> tables;
  std::string out_path;
  SvmTrainOptions base;
  uint64_t max_dt_us = 500000;
  std::string command_line = "uwbnav train-svm";
  for (int i = 1; i < argc; ++i) command_line += std::string(" ") + argv[i];
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](std::string* v) {
      if (i + 1 >= argc) return false;
      *v = argv[++i];
      return true;
    };
    std::string v;
    if (a == "--grouped") {
      base.grouped_cv = true;
    } else if (a == "--verbose") {
      base.verbose = true;
    } else if (!value(&v)) {
      return usage();
    } else if (a == "--features") {
      feature_names = split(v, ',');
    } else if (a == "--sim") {
      sims.push_back(v);
    } else if (a == "--seeds") {
      for (const auto& s : split(v, ',')) seeds.push_back(std::strtoull(s.c_str(), nullptr, 10));
    } else if (a == "--recording") {
      recordings.push_back(v);
    } else if (a == "--table") {
      tables.push_back(v);
    } else if (a == "--out") {
      out_path = v;
    } else if (a == "--folds") {
      base.folds = std::max(2, std::atoi(v.c_str()));
    } else if (a == "--seed") {
      base.seed = std::strtoull(v.c_str(), nullptr, 10);
    } else if (a == "--grid-samples") {
      base.grid_samples = std::strtoull(v.c_str(), nullptr, 10);
    } else if (a == "--max-train") {
      base.max_train_samples = std::strtoull(v.c_str(), nullptr, 10);
    } else if (a == "--capacity") {
      base.capacity = std::min<size_t>(kSvmMaxSupportVectors, std::strtoull(v.c_str(), nullptr, 10));
    } else if (a == "--edit") {
      base.edit_pool = std::strtoull(v.c_str(), nullptr, 10);
    } else if (a == "--max-dt-us") {
      max_dt_us = std::strtoull(v.c_str(), nullptr, 10);
    } else {
      std::fprintf(stderr, "uwbnav train-svm: unknown option %s\n", a.c_str());
      return usage();
    }
  }
  if (feature_names.empty() || (sims.empty() && recordings.empty() && tables.empty()) ||
      (!sims.empty() && seeds.empty())) {
    return usage();
  }
  // Load the data once.
  std::vector<dataset::Recording> recs;
  for (const auto& preset : sims) {
    for (uint64_t seed : seeds) {
      dataset::Recording rec;
      std::string err;
      if (!ok(sim::simulate(preset, seed, rec, &err))) {
        std::fprintf(stderr, "uwbnav train-svm: %s\n", err.c_str());
        return 1;
      }
      recs.push_back(std::move(rec));
    }
  }
  for (const auto& dir : recordings) {
    dataset::Recording rec;
    dataset::ReadReport rr;
    if (!ok(dataset::read_recording(dir, rec, rr))) {
      std::fprintf(stderr, "uwbnav train-svm: %s\n", rr.error.c_str());
      return 1;
    }
    recs.push_back(std::move(rec));
  }
  std::vector<SvmModel> models;
  std::vector<std::string> names;
  std::vector<SvmTrainReport> reports;
  for (const auto& fname : feature_names) {
    SvmFeatureSet set;
    if (!parse_feature_set(fname, &set)) {
      std::fprintf(stderr, "uwbnav train-svm: unknown feature set %s\n", fname.c_str());
      return usage();
    }
    std::vector<SvmSample> samples;
    std::string err;
    for (const auto& rec : recs) {
      if (set == SvmFeatureSet::kChannel && !tables.empty()) break;
      if (!ok(samples_from_recording(rec, set, max_dt_us, samples, &err))) {
        std::fprintf(stderr, "uwbnav train-svm: %s\n", err.c_str());
        return 1;
      }
    }
    if (set == SvmFeatureSet::kChannel) {
      for (const auto& t : tables) {
        if (!ok(samples_from_table(t, set, samples, &err))) {
          std::fprintf(stderr, "uwbnav train-svm: %s\n", err.c_str());
          return 1;
        }
      }
    }
    SvmTrainOptions opt = base;
    opt.set = set;
    SvmModel model;
    SvmTrainReport report;
    std::fprintf(stderr, "train-svm: %s on %zu samples\n", feature_set_name(set), samples.size());
    if (!ok(train_svm_model(samples, opt, model, report, &err))) {
      std::fprintf(stderr, "uwbnav train-svm: %s: %s\n", feature_set_name(set), err.c_str());
      return 1;
    }
    std::printf("%-17s C=%-6g gamma=%-6g %s=%.2f%%  trained %zu/%zu samples  nSV=%zu (capacity %zu, %d retrains)  crc32=%08" PRIX32 "\n",
                feature_set_name(set), report.best_c, report.best_gamma,
                opt.edit_pool > 0 ? "validation_accuracy" : "cv_accuracy", 100.0 * report.best_cv_accuracy,
                report.samples_trained, report.samples_available, report.num_sv, opt.capacity,
                report.capacity_retries, model.crc32);
    models.push_back(model);
    names.emplace_back(model_name(set));
    reports.push_back(report);
  }
  if (!out_path.empty()) {
    std::ofstream o(out_path, std::ios::binary);
    o << export_models_cpp(models, names, reports, command_line);
    if (!o) {
      std::fprintf(stderr, "uwbnav train-svm: cannot write %s\n", out_path.c_str());
      return 1;
    }
    std::printf("wrote %s\n", out_path.c_str());
  }
  return 0;
}

}  // namespace uwbnav::eval
