// Innovation evidence of the default gating policy (docs/nlos.md "Innovation
// evidence"): the likelihood ratio of a range's innovation under NLOS (line-of-
// sight noise plus an exponential excess) against line of sight, as a probability.
#pragma once

namespace uwbnav {

// Clip of the evidence: it stays in [kInnovEvidenceClip, 1 - kInnovEvidenceClip]
// so that strong channel evidence can overrule it.
constexpr float kInnovEvidenceClip = 0.02F;

// Mills ratio of the normal tail, (1 - Phi(t)) / phi(t), for t >= 0 by
// Boerjesson and Sundberg (IEEE Trans. Commun. COM-27(3), 1979); relative
// error < 0.3 %.
float normal_mills_ratio(float t);

// NLOS probability on balanced classes, LR / (1 + LR), of the innovation
// nu_m [m] with innovation variance s_m2 [m^2] when an NLOS range carries an
// excess ~ Exp(mean mu_m) [m]; clipped to [kInnovEvidenceClip, 1 -
// kInnovEvidenceClip]. NaN when nu_m or s_m2 is not finite, s_m2 <= 0 or
// mu_m <= 0.
float innovation_p_nlos(float nu_m, float s_m2, float mu_m);

}  // namespace uwbnav
