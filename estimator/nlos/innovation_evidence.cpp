// Innovation evidence of the default gating policy (docs/nlos.md "Innovation
// evidence"), exponentially modified Gaussian against the line-of-sight normal.
#include "estimator/nlos/innovation_evidence.hpp"

#include <cmath>

#include "estimator/types.hpp"

namespace uwbnav {

// The likelihood ratio of the innovation nu under NLOS, where the range carries
// a positive excess b ~ Exp(mean mu) on top of the LOS error N(0, S) (an
// exponentially modified Gaussian), against LOS, N(0, S):
//   f_nlos(nu) = (1/mu) exp(S/(2 mu^2) - nu/mu) Phi(nu/sqrt(S) - sqrt(S)/mu),
// as a probability on balanced classes, LR / (1 + LR). A range shorter than
// predicted is evidence of line of sight (an NLOS path is never shorter).
// With x = nu/sqrt(S) - sqrt(S)/mu the exponents collect to x^2/2, so
//   LR = (sqrt(S)/mu) Phi(x)/phi(x) = (sqrt(S)/mu) M(-x),
// M the Mills ratio of the normal tail, which falls as 1/|x| for a short range
// (a range 4 sigma short scores about 0.06 at S = 0.02 m^2, mu = 0.5 m). For
// x > 0, Phi(x)/phi(x) = sqrt(2 pi) e^(x^2/2) - M(x). M by Boerjesson and
// Sundberg (IEEE Trans. Commun. COM-27(3), 1979):
//   M(t) = 1 / ((1 - a) t + a sqrt(t^2 + b)), a = 0.339, b = 5.510,
// relative error < 0.3 % for t >= 0; no logarithms (picolibc's logf goes
// through double on the M4F).

float normal_mills_ratio(float t) {
  constexpr float kA = 0.339F;
  constexpr float kB = 5.510F;
  return 1.0F / ((1.0F - kA) * t + kA * std::sqrt(t * t + kB));
}

float innovation_p_nlos(float nu_m, float s_m2, float mu_m) {
  if (!std::isfinite(nu_m) || !(s_m2 > 0.0F) || !std::isfinite(s_m2) || !(mu_m > 0.0F)) return kNaNf;
  const float sd = std::sqrt(s_m2);
  const float x = nu_m / sd - sd / mu_m;
  const float ratio = x <= 0.0F ? normal_mills_ratio(-x)
                                : 2.5066283F * std::exp(std::fmin(0.5F * x * x, 40.0F)) - normal_mills_ratio(x);
  const float lr = sd / mu_m * ratio;
  const float p = lr / (1.0F + lr);
  if (!std::isfinite(p)) return 1.0F - kInnovEvidenceClip;
  return std::fmin(std::fmax(p, kInnovEvidenceClip), 1.0F - kInnovEvidenceClip);
}

}  // namespace uwbnav
