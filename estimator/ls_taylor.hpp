// LS-Taylor multilateration (seed 003 eq. 1-4): a regularised linear
// least-squares fix as the starting point of Gauss-Newton iterations on the
// range equations; 3-D mode and a 2-D mode with known tag height.
// Used for filter initialisation, the LS-UWB baseline and RAIM (seed 001).
#pragma once

#include <cstddef>
#include <cstdint>

#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav {

// One epoch holds at most one range per anchor (callers solve per tag: the
// initial fix, RAIM, the LS-UWB baseline), so the capacity is the anchor table's.
constexpr size_t kLsMaxRanges = kMaxAnchors;

struct LsRange {
  Vec3f anchor_pos_nav_m;  // anchor antenna [m]
  float range_m = 0.0F;    // measured range [m]
  float sigma_m = 0.1F;    // 1-sigma of the range [m] (weights)
};

struct LsOptions {
  bool two_d = false;          // solve x,y only with z fixed to known_z_m (planar anchor layouts)
  float known_z_m = 0.0F;      // tag antenna height used in 2-D mode [m]
  bool has_initial_guess = false;
  Vec3f initial_guess_nav_m;   // start of Gauss-Newton instead of the linear fix
  uint8_t max_iterations = 10;
  float tolerance_m = 1e-4F;   // stop when the step is below this [m]
  float regularisation = 1e-6F;  // Tikhonov term of the linear step (relative) [-]
};

struct LsFix {
  Vec3f pos_nav_m;               // tag antenna position [m]
  float cov_nav_m2[3][3] = {};   // (H^T W H)^-1 at the solution [m^2]
  float residual_m[kLsMaxRanges] = {};  // measured - predicted, per input range [m]
  float weighted_ssr = 0.0F;     // sum (residual/sigma)^2 [-] (seed 001 chi-square statistic)
  float gdop = 0.0F;             // geometric dilution of precision [-]
  uint8_t iterations = 0;
  uint8_t dof = 0;               // n - unknowns
  bool converged = false;
};

// Solves for the tag antenna position. kInvalidArgument: n too small for the
// mode (3-D needs >= 4 ranges for redundancy-free fix with 4 anchors, >= 3
// accepted with an initial guess; 2-D needs >= 3, >= 2 with initial guess) or
// non-finite inputs. kSingular: geometry too poor (colinear/coplanar anchors in
// 3-D) - the caller may retry in 2-D mode. Never returns a non-finite fix.
[[nodiscard]] Status ls_taylor_solve(const LsRange* ranges, size_t n, const LsOptions& options, LsFix& fix);

}  // namespace uwbnav
