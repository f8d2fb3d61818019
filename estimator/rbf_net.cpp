// RbfNet: Gaussian RBF network (seed 004 eq. 9-11), output weights by
// recursive least squares with exponential forgetting, local residual variance.
#include "estimator/rbf_net.hpp"

#include <cmath>

namespace uwbnav {

RbfNet::RbfNet() { reset(); }

void RbfNet::configure(const Centres& centres, Real width, const Settings& settings) {
  set_ = settings;
  centres_ = centres;
  if (!(width > Real(0))) {
    // Seed 004 eq. 11: sigma = c_max / sqrt(2 h).
    Real c_max = Real(0);
    for (int i = 0; i < kCentres; ++i) {
      for (int j = i + 1; j < kCentres; ++j) c_max = std::fmax(c_max, (centres_.col(i) - centres_.col(j)).norm());
    }
    width = c_max / std::sqrt(Real(2) * static_cast<Real>(kCentres));
  }
  width_ = width > Real(0) ? width : Real(1);
  inv_two_width2_ = Real(1) / (Real(2) * width_ * width_);
  reset();
}

void RbfNet::reset() {
  w_.setZero();
  p_.setIdentity();
  p_ *= set_.weight_prior;
  resid_var_.setConstant(set_.resid_prior_var);
  exposure_.setZero();
  calib_.setOnes();
  calib_count_ = Real(0);
  samples_ = 0;
  phi_.setZero();
  k_.setZero();
}

void RbfNet::regressor(const Input& x, Regressor& phi) const {
  for (int i = 0; i < kCentres; ++i) {
    phi(i) = std::exp(-(x - centres_.col(i)).squaredNorm() * inv_two_width2_);
  }
  phi(kCentres) = Real(1);
}

void RbfNet::train(const Input& x, const Output& target) {
  if (!x.allFinite() || !target.allFinite()) return;
  const Prediction claim = predict(x);
  if (claim.valid) {
    if (calib_count_ < set_.resid_window) calib_count_ += Real(1);
    for (int k = 0; k < kOutputs; ++k) {
      const Real e = target(k) - claim.y(k);
      // Against the uncalibrated variance (the factor itself is what is estimated).
      const Real raw_var = claim.var(k) / std::fmax(calib_(k), Real(1));
      const Real z2 = raw_var > Real(0) ? e * e / raw_var : Real(1);
      calib_(k) += (z2 - calib_(k)) / (calib_count_ + Real(2));
    }
  }
  regressor(x, phi_);
  // A-priori residual (before this sample moves the weights): an honest,
  // out-of-sample error of the network near x.
  const Output resid = target - w_.transpose() * phi_;
  const Real act_sum = phi_.head<kCentres>().sum();
  if (act_sum > Real(1e-6)) {
    for (int i = 0; i < kCentres; ++i) {
      const Real a = phi_(i) / act_sum;  // this sample's share at centre i
      exposure_(i) = std::fmin(exposure_(i) + a, set_.resid_window);
      const Real gain = a / (exposure_(i) + Real(2));  // prior counts as two samples
      for (int k = 0; k < kOutputs; ++k) {
        resid_var_(i, k) += gain * (resid(k) * resid(k) - resid_var_(i, k));
      }
    }
  }
  // RLS (seed 004 eq. 10 solved recursively): k = P phi / (lambda + phi^T P phi),
  // W += k e^T, P = (P - k phi^T P) / lambda. Forgetting only while the
  // covariance is below its prior (no wind-up of directions the data do not excite).
  const Real lambda = set_.forgetting;
  k_.noalias() = p_ * phi_;
  const Real denom = lambda + phi_.dot(k_);
  if (!(denom > Real(0)) || !std::isfinite(denom)) return;
  k_ /= denom;
  w_.noalias() += k_ * resid.transpose();
  p_.noalias() -= k_ * (phi_.transpose() * p_);
  bool room = true;
  for (int i = 0; i < kRegressors; ++i) room = room && p_(i, i) <= set_.weight_prior * lambda;
  if (room) p_ /= lambda;
  p_ = Real(0.5) * (p_ + p_.transpose()).eval();
  ++samples_;
}

RbfNet::Prediction RbfNet::predict(const Input& x) const {
  Prediction out;
  if (samples_ == 0 || !x.allFinite()) return out;
  Regressor phi;
  regressor(x, phi);
  const Real act_sum = phi.head<kCentres>().sum();
  if (!(act_sum >= set_.min_activation)) return out;  // outside the domain of the centres
  Real trained_act = Real(0);
  Output local = Output::Zero();
  for (int i = 0; i < kCentres; ++i) {
    if (exposure_(i) >= set_.min_exposure) trained_act += phi(i);
    local += (phi(i) / act_sum) * resid_var_.row(i).transpose();
  }
  out.coverage = trained_act / act_sum;
  if (!(out.coverage >= set_.min_coverage)) return out;
  // Error variance: local residual variance times (1 + phi^T P phi), the
  // weights' own uncertainty in units of the residual variance (RLS).
  const Real param = phi.dot(p_ * phi);
  out.y = w_.transpose() * phi;
  out.var = local * (Real(1) + std::fmax(param, Real(0)));
  for (int k = 0; k < kOutputs; ++k) out.var(k) *= std::fmax(calib_(k), Real(1));
  out.valid = out.y.allFinite() && out.var.allFinite();
  if (!out.valid) {
    out.y.setZero();
    out.var.setZero();
  }
  return out;
}

}  // namespace uwbnav
