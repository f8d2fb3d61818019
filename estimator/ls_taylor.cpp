// LS-Taylor multilateration (seed 003 eq. 1-4): weighted, regularised linear
// least squares on differences of squared ranges, then Gauss-Newton on the
// range equations; 3-D and 2-D (known tag height) modes. Static memory only.
#include "estimator/ls_taylor.hpp"

#include <Eigen/Dense>
#include <cmath>

namespace uwbnav {
namespace {

using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;

// Weakest/strongest eigenvalue ratio of a (normalised) information matrix
// below which the geometry is declared singular: the weakest direction would be
// 100x less precise (in sigma) than the strongest.
constexpr Real kMinEigenRatio = static_cast<Real>(1e-4);
// Ranges closer than this to the current estimate give no direction (tag on
// the anchor): their Jacobian row is dropped for that iteration [m].
constexpr Real kMinDirectionRange_m = static_cast<Real>(1e-3);
// A Gauss-Newton step longer than this is divergence, not refinement [m].
constexpr Real kMaxStep_m = static_cast<Real>(1e4);
// Variance reported per axis when no fix could be computed [m^2].
constexpr float kFailVariance_m2 = 1e6F;

Vec3 to_vec(const Vec3f& v) { return Vec3(static_cast<Real>(v.x), static_cast<Real>(v.y), static_cast<Real>(v.z)); }

Vec3f to_vec3f(const Vec3& v) {
  return Vec3f{static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

bool finite3(const Vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Smallest/largest eigenvalue ratio of the leading m x m block (m = 2 or 3).
// Returns 0 for a zero or non-finite matrix. 2x2: closed form (Eigen
// computeDirect, exact to float rounding), a fraction of the iterative QR
// solver's cost per Gauss-Newton step. 3x3 stays iterative: the closed form
// (trigonometric, from the characteristic polynomial) loses the small
// eigenvalue of near-planar layouts in float and moves fixes across
// kMinEigenRatio (measured: 2 % fewer LS-Taylor epochs on hanyang_los_trajA).
Real eigen_ratio(const Mat3& n, int m) {
  if (!n.allFinite()) return Real(0);
  if (m == 2) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Real, 2, 2>> es;
    es.computeDirect(n.template topLeftCorner<2, 2>(), Eigen::EigenvaluesOnly);
    const Real hi = es.eigenvalues()(1);
    return hi > Real(0) ? es.eigenvalues()(0) / hi : Real(0);
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> es(n, Eigen::EigenvaluesOnly);
  const Real hi = es.eigenvalues()(2);
  return hi > Real(0) ? es.eigenvalues()(0) / hi : Real(0);
}

// Inverse of the leading m x m block, embedded in a 3x3 (zeros elsewhere).
Mat3 inverse_block(const Mat3& n, int m) {
  if (m != 2) return n.inverse();
  Mat3 out = Mat3::Zero();
  out.template topLeftCorner<2, 2>() = n.template topLeftCorner<2, 2>().inverse();
  return out;
}

void fail_fix(const LsOptions& options, LsFix& fix) {
  fix = LsFix{};
  if (options.has_initial_guess && finite3(options.initial_guess_nav_m)) {
    fix.pos_nav_m = options.initial_guess_nav_m;
  }
  for (int i = 0; i < 3; ++i) fix.cov_nav_m2[i][i] = kFailVariance_m2;
}

// Linear fix (seed 003 eq. 2-3) in coordinates relative to `origin`. The
// reference equation is the range with the smallest d*sigma (least noise on
// d^2); each difference row is weighted by 1/var(d_i^2 - d_ref^2) ~ 1/(4 d^2 s^2).
Status linear_fix(const LsRange* ranges, size_t n, const LsOptions& options, int m, const Vec3& origin,
                  Vec3& out_rel) {
  size_t ref = 0;
  Real best = Real(0);
  for (size_t i = 0; i < n; ++i) {
    const Real ds = std::fabs(static_cast<Real>(ranges[i].range_m)) * static_cast<Real>(ranges[i].sigma_m);
    if (i == 0 || ds < best) {
      best = ds;
      ref = i;
    }
  }
  const Real z_rel = static_cast<Real>(options.known_z_m) - origin.z();
  // Squared horizontal (2-D) or full (3-D) range to each anchor.
  auto range_sq = [&](size_t i) {
    const Real d = static_cast<Real>(ranges[i].range_m);
    Real d2 = d * d;
    if (m == 2) {
      const Real dz = to_vec(ranges[i].anchor_pos_nav_m).z() - origin.z() - z_rel;
      d2 -= dz * dz;  // slant -> horizontal (may go negative with noise; stays linear)
    }
    return d2;
  };
  const Vec3 a_ref = to_vec(ranges[ref].anchor_pos_nav_m) - origin;
  const Real d2_ref = range_sq(ref);
  const Real var_ref = [&] {
    const Real d = static_cast<Real>(ranges[ref].range_m);
    const Real s = static_cast<Real>(ranges[ref].sigma_m);
    return d * d * s * s;
  }();

  Mat3 ata = Mat3::Zero();
  Vec3 atb = Vec3::Zero();
  for (size_t i = 0; i < n; ++i) {
    if (i == ref) continue;
    const Vec3 a_i = to_vec(ranges[i].anchor_pos_nav_m) - origin;
    Vec3 row = a_i - a_ref;  // seed 003 eq. 2, matrix A
    if (m == 2) row.z() = Real(0);
    Real sq_i = a_i.squaredNorm();
    Real sq_ref = a_ref.squaredNorm();
    if (m == 2) {
      sq_i -= a_i.z() * a_i.z();
      sq_ref -= a_ref.z() * a_ref.z();
    }
    const Real b = Real(0.5) * (sq_i - sq_ref + d2_ref - range_sq(i));  // seed 003 eq. 2, vector b
    const Real d = static_cast<Real>(ranges[i].range_m);
    const Real s = static_cast<Real>(ranges[i].sigma_m);
    // Floor the variance at 1 mm^2 * |row|^2 so a zero range cannot give an infinite weight.
    const Real var = d * d * s * s + var_ref + Real(1e-6) * (row.squaredNorm() + Real(1));
    const Real w = Real(1) / var;
    ata.noalias() += w * row * row.transpose();
    atb.noalias() += w * b * row;
  }
  if (eigen_ratio(ata, m) < kMinEigenRatio) return Status::kSingular;

  // Regularised LS with the first-order correction term (seed 003 eq. 3):
  // xi = M^-1 R M^-1 A^T b + M^-1 A^T b, M = A^T A + R, R = lambda I.
  const Real lambda = static_cast<Real>(options.regularisation) * ata.trace() / static_cast<Real>(m);
  Mat3 reg = Mat3::Zero();
  for (int k = 0; k < m; ++k) reg(k, k) = lambda;
  const Mat3 m_inv = inverse_block(ata + reg, m);
  const Vec3 base = m_inv * atb;
  out_rel = m_inv * (reg * base) + base;
  if (m == 2) out_rel.z() = z_rel;
  return out_rel.allFinite() ? Status::kOk : Status::kSingular;
}

}  // namespace

Status ls_taylor_solve(const LsRange* ranges, size_t n, const LsOptions& options, LsFix& fix) {
  fail_fix(options, fix);
  const int m = options.two_d ? 2 : 3;
  if (ranges == nullptr || n > kLsMaxRanges) return Status::kInvalidArgument;
  const size_t min_n = static_cast<size_t>(m + 1) - (options.has_initial_guess ? 1U : 0U);
  if (n < min_n) return Status::kInvalidArgument;
  if (options.has_initial_guess && !finite3(options.initial_guess_nav_m)) return Status::kInvalidArgument;
  if (options.two_d && !std::isfinite(options.known_z_m)) return Status::kInvalidArgument;
  if (!std::isfinite(options.tolerance_m) || !std::isfinite(options.regularisation)) {
    return Status::kInvalidArgument;
  }
  for (size_t i = 0; i < n; ++i) {
    if (!finite3(ranges[i].anchor_pos_nav_m) || !std::isfinite(ranges[i].range_m) ||
        !std::isfinite(ranges[i].sigma_m) || !(ranges[i].sigma_m > 0.0F)) {
      return Status::kInvalidArgument;
    }
  }

  // Work relative to the anchor centroid: keeps squared coordinates small in float.
  Vec3 origin = Vec3::Zero();
  for (size_t i = 0; i < n; ++i) origin += to_vec(ranges[i].anchor_pos_nav_m);
  origin /= static_cast<Real>(n);

  Vec3 x_rel = Vec3::Zero();
  if (options.has_initial_guess) {
    x_rel = to_vec(options.initial_guess_nav_m) - origin;
    if (options.two_d) x_rel.z() = static_cast<Real>(options.known_z_m) - origin.z();
  } else {
    const Status st = linear_fix(ranges, n, options, m, origin, x_rel);
    if (st != Status::kOk) return st;
  }

  // Gauss-Newton on the range equations (seed 003 eq. 4), weighted by 1/sigma^2.
  Mat3 info = Mat3::Zero();   // H^T W H
  Mat3 geom = Mat3::Zero();   // H^T H (GDOP)
  bool converged = false;
  uint8_t iterations = 0;
  const Real tol = static_cast<Real>(options.tolerance_m);
  for (uint8_t it = 0; it <= options.max_iterations; ++it) {
    info.setZero();
    geom.setZero();
    Vec3 htwe = Vec3::Zero();
    for (size_t i = 0; i < n; ++i) {
      const Vec3 diff = x_rel - (to_vec(ranges[i].anchor_pos_nav_m) - origin);
      const Real r = diff.norm();
      if (r < kMinDirectionRange_m) continue;  // tag on the anchor: no direction information
      Vec3 h = diff / r;                       // seed 003 eq. 4, row i
      if (m == 2) h.z() = Real(0);
      const Real s = static_cast<Real>(ranges[i].sigma_m);
      const Real w = Real(1) / (s * s);
      const Real e = static_cast<Real>(ranges[i].range_m) - r;
      info.noalias() += w * h * h.transpose();
      geom.noalias() += h * h.transpose();
      htwe.noalias() += (w * e) * h;
    }
    if (eigen_ratio(info, m) < kMinEigenRatio) return Status::kSingular;
    // The last pass only evaluates the information matrix at the final point.
    if (it == options.max_iterations || converged) break;
    const Vec3 step = inverse_block(info, m) * htwe;
    if (!step.allFinite() || step.norm() > kMaxStep_m) return Status::kSingular;
    x_rel += step;
    if (m == 2) x_rel.z() = static_cast<Real>(options.known_z_m) - origin.z();
    iterations = static_cast<uint8_t>(it + 1);
    if (step.norm() < tol) converged = true;
  }

  const Vec3 pos = x_rel + origin;
  const Mat3 cov = inverse_block(info, m);
  const Mat3 geom_inv = inverse_block(geom, m);
  if (!pos.allFinite() || !cov.allFinite() || !geom_inv.allFinite()) return Status::kSingular;

  Real wssr = Real(0);
  for (size_t i = 0; i < n; ++i) {
    const Real r = (x_rel - (to_vec(ranges[i].anchor_pos_nav_m) - origin)).norm();
    const Real e = static_cast<Real>(ranges[i].range_m) - r;
    const Real s = static_cast<Real>(ranges[i].sigma_m);
    fix.residual_m[i] = static_cast<float>(e);
    wssr += (e / s) * (e / s);
  }
  fix.pos_nav_m = to_vec3f(pos);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) fix.cov_nav_m2[r][c] = static_cast<float>(cov(r, c));
  }
  fix.weighted_ssr = static_cast<float>(wssr);
  fix.gdop = static_cast<float>(std::sqrt(std::fmax(geom_inv.trace(), Real(0))));
  fix.iterations = iterations;
  fix.dof = static_cast<uint8_t>(n - static_cast<size_t>(m));
  fix.converged = converged;
  if (!std::isfinite(fix.weighted_ssr) || !std::isfinite(fix.gdop)) {
    fail_fix(options, fix);
    return Status::kSingular;
  }
  return Status::kOk;
}

}  // namespace uwbnav
