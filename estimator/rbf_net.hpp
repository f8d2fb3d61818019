// Fixed-capacity Gaussian radial-basis-function network (seed 004 §2.2, eq. 9-11)
// with its output weights learnt on line by recursive least squares and a
// local estimate of its own prediction error. Static memory only: centres,
// widths, weights and the RLS covariance are fixed-size members.
#pragma once

#include <cstdint>

#include "estimator/ekf_state.hpp"

namespace uwbnav {

class RbfNet {
 public:
  static constexpr int kInputs = 3;    // p of seed 004 fig. 2
  static constexpr int kCentres = 16;  // h (hidden neurons) of eq. 10-11
  static constexpr int kOutputs = 2;   // n of fig. 2
  static constexpr int kRegressors = kCentres + 1;  // the Gaussians and a constant (output bias)

  using Input = Eigen::Matrix<Real, kInputs, 1>;
  using Output = Eigen::Matrix<Real, kOutputs, 1>;
  using Regressor = Eigen::Matrix<Real, kRegressors, 1>;
  using Centres = Eigen::Matrix<Real, kInputs, kCentres>;

  struct Prediction {
    Output y = Output::Zero();    // network output (zero when not valid)
    Output var = Output::Zero();  // variance of its error per output [output unit^2]
    Real coverage = Real(0);      // share of the activation on trained centres [0, 1]
    bool valid = false;           // trained near x: usable
  };

  // Learning settings. Units: those of the outputs (squared) for the variances.
  struct Settings {
    Real forgetting = Real(0.998);     // RLS forgetting factor per sample (lambda)
    Real weight_prior = Real(10);      // prior weight variance / residual variance (P0 = weight_prior * I)
    Real resid_prior_var = Real(1);    // residual variance assumed before any sample [unit^2]
    Real resid_window = Real(200);     // activation-weighted samples the residual variance averages over
    Real min_exposure = Real(20);      // samples' activation shares a centre needs before it counts as trained
    Real min_coverage = Real(0.9);     // share of activation on trained centres for a valid prediction
    Real min_activation = Real(0.05);  // total activation below which x is outside the network's domain
  };

  RbfNet();

  // Centres (columns) and one common Gaussian width; width <= 0 takes seed 004
  // eq. 11: sigma = c_max / sqrt(2 h), c_max the largest distance between two centres.
  void configure(const Centres& centres, Real width, const Settings& settings);
  // Forgets everything learnt (weights, covariance, residuals): untrained.
  void reset();

  // One on-line training sample: RLS step on the output weights (shared
  // regressor, so one covariance serves every output) and the local a-priori
  // residual variance. Before learning from it, the sample checks the
  // network's claim: the running mean of (error / claimed sigma)^2 of valid
  // predictions scales every later variance when it exceeds 1 (self-calibration).
  // Non-finite samples are ignored.
  void train(const Input& x, const Output& target);
  // Output and error variance at x; not valid (zero output) where untrained.
  Prediction predict(const Input& x) const;

  bool trained() const { return samples_ > 0; }
  uint32_t samples() const { return samples_; }
  Real width() const { return width_; }
  const Centres& centres() const { return centres_; }

 private:
  // Gaussian activations phi_i(x) = exp(-|x - c_i|^2 / (2 sigma^2)) (seed 004 eq. 9) and the constant.
  void regressor(const Input& x, Regressor& phi) const;

  Settings set_;
  Centres centres_ = Centres::Zero();
  Real width_ = Real(1);
  Real inv_two_width2_ = Real(0.5);
  Eigen::Matrix<Real, kRegressors, kOutputs> w_;           // output weights W (eq. 10, learnt by RLS)
  Eigen::Matrix<Real, kRegressors, kRegressors> p_;        // RLS covariance / residual variance
  Eigen::Matrix<Real, kCentres, kOutputs> resid_var_;      // local a-priori residual variance per centre [unit^2]
  Eigen::Matrix<Real, kCentres, 1> exposure_;              // samples' shares of activation per centre (saturates at resid_window)
  Output calib_ = Output::Ones();                          // mean squared normalised a-priori error (>= 1 used)
  Real calib_count_ = Real(0);                             // samples in calib_ (saturates at resid_window)
  uint32_t samples_ = 0;
  // Scratch (members, not function statics).
  Regressor phi_;
  Regressor k_;
};

}  // namespace uwbnav
