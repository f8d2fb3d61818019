// Multi-sensor consistency model of seed 000 §1.2(2), eq. 3-6: the range change
// of one anchor/tag pair between consecutive ranges against the distance the
// vehicle travelled meanwhile (triangle inequality), mapped to p2.
#pragma once

namespace uwbnav {

// Excess |Δρ_k| - Δd_k [m] of eq. 4-5. NaN when an input is not finite.
float consistency_excess_m(float delta_range_m, float dist_travelled_m);

// p2 of eq. 6 from the excess and σ_UWB [m]:
// <= σ: 0.35, > σ: 0.55, > 2σ: 0.7, > 3σ: 0.9. NaN when an input is not finite or σ <= 0.
float consistency_p_nlos(float delta_range_m, float dist_travelled_m, float sigma_uwb_m);

}  // namespace uwbnav
