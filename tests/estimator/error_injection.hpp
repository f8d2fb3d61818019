// The error-state injection of EkfCore (ekf_state.hpp conventions) for tests
// that perturb a nominal state: numeric Jacobians, Monte-Carlo truths.
#pragma once

#include "estimator/ekf_state.hpp"

namespace uwbnav::test {

inline NominalState inject(const NominalState& x, const ErrVec& dx) {
  NominalState y = x;
  y.pos_nav_m += dx.segment<3>(ErrIdx::kPos);
  y.vel_nav_mps += dx.segment<3>(ErrIdx::kVel);
  y.q_nav_body = quat_normalised(quat_mul(quat_exp(dx.segment<3>(ErrIdx::kAtt)), x.q_nav_body));
  y.ba_body_mps2 += dx.segment<3>(ErrIdx::kBa);
  y.bg_body_radps += dx.segment<3>(ErrIdx::kBg);
  y.range_err += dx.tail<ErrIdx::kRange>();
  return y;
}

}  // namespace uwbnav::test
