// Dempster-Shafer combination of two NLOS/LOS basic probability assignments
// (seed 000 §1.2(3), eq. 7-8) over the frame {N, L}.
#pragma once

#include <cstddef>

namespace uwbnav {

// R = p1 p2 / (p1 p2 + q1 q2), q = 1 - p (eq. 7-8). A NaN input is absent
// evidence (the other one is returned); both NaN gives NaN. Inputs are clipped
// to [1e-6, 1 - 1e-6] so total conflict (K = 0) cannot occur.
float ds_combine(float p1, float p2);

// Orthogonal sum of n assignments (left fold of ds_combine); NaN entries ignored.
float ds_combine_all(const float* p, size_t n);

}  // namespace uwbnav
