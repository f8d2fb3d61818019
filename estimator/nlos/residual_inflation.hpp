// Residual-based measurement-noise inflation of seed 003 §2.3, eq. 21-25.
#pragma once

namespace uwbnav {

// Noise factor e_i of eq. 23 from the residual δ_i (eq. 21) and threshold Th
// (same unit as δ_i): 1 when δ_i <= Th, β δ_i / Th otherwise. NaN for
// non-finite inputs or Th <= 0. uwbnav applies it multiplicatively
// (R' = e_i R, docs/nlos.md): eq. 25 adds a unitless e_i to R, which would
// inflate every LOS range too.
float residual_inflation_factor(float residual, float threshold, float beta);

}  // namespace uwbnav
