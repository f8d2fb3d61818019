// LAMBDA integer least squares (estimator/lambda.*): published test vectors
// (RTKLIB's unit test, the de Jonge & Tiberius 3-D example), exhaustive
// enumeration on random correlated problems, properties of the decorrelation,
// refused inputs, the ratio test, and the cost per solve (printed, not asserted).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

#include "estimator/lambda.hpp"
#include "estimator/types.hpp"

namespace uwbnav {
namespace {

// LAMBDA runs in double in both estimator builds (float default, and the
// UWBNAV_ESTIMATOR_DOUBLE copy uwbnav_estimator_f64 that also compiles
// estimator/lambda.cpp); its types must not follow Real.
static_assert(std::is_same<LambdaMat::Scalar, double>::value, "LAMBDA works in double");
static_assert(std::is_same<LambdaVec::Scalar, double>::value, "LAMBDA works in double");

LambdaVec vec_of(std::initializer_list<double> v) {
  LambdaVec out = LambdaVec::Zero();
  int i = 0;
  for (double x : v) out(i++) = x;
  return out;
}

// Row-major n x n values into the leading block (the rest zero).
LambdaMat mat_of(int n, std::initializer_list<double> v) {
  LambdaMat out = LambdaMat::Zero();
  int k = 0;
  for (double x : v) {
    out(k / n, k % n) = x;
    ++k;
  }
  return out;
}

// Leading n x n block of q padded with the identity (fixed size: the
// estimator headers carry EIGEN_NO_MALLOC into this test).
LambdaMat padded(const LambdaMat& q, int n) {
  LambdaMat p = LambdaMat::Identity();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) p(i, j) = q(i, j);
  }
  return p;
}

// (a_hat - a)^T Q^-1 (a_hat - a) by a Cholesky factor of Q, independent of the solver.
double direct_sq_norm(const LambdaVec& a_hat, const LambdaMat& q, int n, const LambdaVec& a) {
  const Eigen::LLT<LambdaMat> llt(padded(q, n));
  LambdaVec r = LambdaVec::Zero();
  for (int i = 0; i < n; ++i) r(i) = a_hat(i) - a(i);
  const LambdaVec w = llt.matrixL().solve(r);
  return w.squaredNorm();
}

// Conditional variances of Q in the solver's order (variance of a_k given
// a_0..a_{k-1}): the squared diagonal of the Cholesky factor Q = R R^T.
LambdaVec conditional_variances(const LambdaMat& q, int n) {
  const Eigen::LLT<LambdaMat> llt(padded(q, n));
  const LambdaMat r = llt.matrixL();
  LambdaVec d = LambdaVec::Zero();
  for (int i = 0; i < n; ++i) d(i) = r(i, i) * r(i, i);
  return d;
}

// Random symmetric positive definite Q = U diag(lambda) U^T on the leading
// n x n block: U a random rotation (Gram-Schmidt of Gaussian vectors),
// eigenvalues log-spread over [lambda_max / cond, lambda_max], both ends taken.
LambdaMat random_spd(std::mt19937_64& rng, int n, double lambda_max, double cond) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  LambdaMat u = LambdaMat::Zero();
  for (int c = 0; c < n; ++c) {
    for (;;) {
      for (int r = 0; r < n; ++r) u(r, c) = gauss(rng);
      for (int p = 0; p < c; ++p) {
        const double dot = u.col(p).dot(u.col(c));
        u.col(c) -= dot * u.col(p);
      }
      const double norm = u.col(c).norm();
      if (norm > 1e-3) {
        u.col(c) /= norm;
        break;
      }
    }
  }
  LambdaVec lambda = LambdaVec::Zero();
  for (int i = 0; i < n; ++i) {
    const double t = i == 0 ? 0.0 : (i == 1 ? 1.0 : unit(rng));
    lambda(i) = lambda_max * std::pow(cond, -t);
  }
  LambdaMat q = LambdaMat::Zero();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      double s = 0.0;
      for (int k = 0; k < n; ++k) s += u(i, k) * lambda(k) * u(j, k);
      q(i, j) = s;
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < i; ++j) q(j, i) = q(i, j);  // exactly symmetric
  }
  return q;
}

// GNSS-like double-difference ambiguity covariance, two frequencies: n/2 DDs
// per frequency correlated 0.5 (common reference satellite), L2 = gamma * L1
// plus a small independent part (Q = sigma^2 kron(F, C) + 1e-4 A A^T / n), the
// shape of RTKLIB's utest2 Q. The float a_hat = truth + N(0, Q) noise.
void gnss_like(std::mt19937_64& rng, int n, LambdaMat& q, LambdaVec& a_hat, LambdaVec& truth) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int m = n / 2;
  const double gamma = 77.0 / 60.0;  // f_L1 / f_L2
  const double eps = 1e-3;           // L2's own share
  const double sigma2 = 0.02 + 0.3 * unit(rng);
  q.setZero();
  for (int f1 = 0; f1 < 2; ++f1) {
    for (int f2 = 0; f2 < 2; ++f2) {
      const double fac = (f1 == 0 ? 1.0 : gamma) * (f2 == 0 ? 1.0 : gamma) + (f1 == 1 && f2 == 1 ? eps : 0.0);
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) q(f1 * m + i, f2 * m + j) = sigma2 * fac * (i == j ? 1.0 : 0.5);
      }
    }
  }
  LambdaMat a = LambdaMat::Zero();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) a(i, j) = gauss(rng);
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j) {
      double s = 0.0;
      for (int k = 0; k < n; ++k) s += a(i, k) * a(j, k);
      q(i, j) += 1e-4 * s / n;
      q(j, i) = q(i, j);
    }
  }
  const Eigen::LLT<LambdaMat> llt(padded(q, n));
  const LambdaMat r = llt.matrixL();
  LambdaVec e = LambdaVec::Zero();
  for (int i = 0; i < n; ++i) e(i) = gauss(rng);
  const LambdaVec noise = r * e;
  truth.setZero();
  a_hat.setZero();
  for (int i = 0; i < n; ++i) {
    truth(i) = std::round(2e6 * (unit(rng) - 0.5));
    a_hat(i) = truth(i) + noise(i);
  }
}

// ---------------------------------------------------------------------------
// Published test vectors.
//
// RTKLIB's LAMBDA unit test: repository tomojitakasu/RTKLIB, file
// test/utest/t_lambda.c (utest1, utest2; commit e339c933 as stored). Numbers
// only: float ambiguities a1/a2, covariances Q1/Q2, expected fixed integers
// F1/F2 (best, second) and squared residual norms s1/s2. RTKLIB checks them to
// 1e-4 (its s are printed to 6 decimals); so do we.

TEST(LambdaRtklibVectors, Utest1SixAmbiguitiesGiveRtklibsIntegersAndNorms) {
  const int n = 6;
  const LambdaVec a = vec_of({1585184.171, -6716599.430, 3915742.905, 7627233.455, 9565990.879, 989457273.200});
  const LambdaMat q = mat_of(n, {
      0.227134, 0.112202, 0.112202, 0.112202, 0.112202, 0.103473,
      0.112202, 0.227134, 0.112202, 0.112202, 0.112202, 0.103473,
      0.112202, 0.112202, 0.227134, 0.112202, 0.112202, 0.103473,
      0.112202, 0.112202, 0.112202, 0.227134, 0.112202, 0.103473,
      0.112202, 0.112202, 0.112202, 0.112202, 0.227134, 0.103473,
      0.103473, 0.103473, 0.103473, 0.103473, 0.103473, 0.434339});
  const LambdaVec best = vec_of({1585184, -6716599, 3915743, 7627234, 9565991, 989457273});
  const LambdaVec second = vec_of({1585184, -6716600, 3915743, 7627233, 9565991, 989457273});
  LambdaSolver solver;
  LambdaFix fix;
  ASSERT_EQ(solver.solve(a, q, n, fix), Status::kOk);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(fix.best_cyc(i), best(i), 1e-4) << i;
    EXPECT_NEAR(fix.second_cyc(i), second(i), 1e-4) << i;
  }
  EXPECT_NEAR(fix.best_sq_norm, 3.507984, 1e-4);
  EXPECT_NEAR(fix.second_sq_norm, 3.708456, 1e-4);
  // Exact rational arithmetic (Python fractions, computed for this test) on
  // the double values of the published numbers (989457273.2 is 989457273.20000005
  // in double, which moves the norms by 1e-7 from the decimal-exact 3.50798437).
  EXPECT_NEAR(fix.best_sq_norm, 3.5079844666096394, 1e-12 * 3.5);
  EXPECT_NEAR(fix.second_sq_norm, 3.7084561883796554, 1e-12 * 3.7);
  std::printf("RTKLIB utest1: norms %.16g %.16g (exact 3.5079844666096394 3.7084561883796554)\n", fix.best_sq_norm,
              fix.second_sq_norm);
  // RTKLIB's ratio for these numbers is 1.06: not fixed at seed 002's 3.
  EXPECT_NEAR(fix.ratio, 3.708456 / 3.507984, 1e-4);
  EXPECT_FALSE(fix.fixed);
}

// utest2's numbers: 5 double differences on L1 then the same 5 on L2.
void rtklib_utest2(LambdaVec& a, LambdaMat& q) {
  const int n = 10;
  a = vec_of({-13324172.755747, -10668894.713608, -7157225.010770, -6149367.974367, -7454133.571066,
              -5969200.494550, 8336734.058423, 6186974.084502, -17549093.883655, -13970158.922370});
  const double p = 0.446320, h = 0.223160, c = 0.572775, g = 0.286388, r = 0.735063, s = 0.367531;
  q = mat_of(n, {
      p, h, h, h, h, c, g, g, g, g,
      h, p, h, h, h, g, c, g, g, g,
      h, h, p, h, h, g, g, c, g, g,
      h, h, h, p, h, g, g, g, c, g,
      h, h, h, h, p, g, g, g, g, c,
      c, g, g, g, g, r, s, s, s, s,
      g, c, g, g, g, s, r, s, s, s,
      g, g, c, g, g, s, s, r, s, s,
      g, g, g, c, g, s, s, s, r, s,
      g, g, g, g, c, s, s, s, s, r});
}

TEST(LambdaRtklibVectors, Utest2TenDualFrequencyAmbiguitiesGiveRtklibsIntegersAndNorms) {
  const int n = 10;
  LambdaVec a;
  LambdaMat q;
  rtklib_utest2(a, q);
  const LambdaVec best = vec_of({-13324188, -10668901, -7157236, -6149379, -7454143, -5969220, 8336726, 6186960,
                                 -17549108, -13970171});
  const LambdaVec second = vec_of({-13324188, -10668908, -7157236, -6149379, -7454143, -5969220, 8336717, 6186960,
                                   -17549108, -13970171});
  LambdaSolver solver;
  LambdaFix fix;
  ASSERT_EQ(solver.solve(a, q, n, fix), Status::kOk);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(fix.best_cyc(i), best(i), 1e-4) << i;
    EXPECT_NEAR(fix.second_cyc(i), second(i), 1e-4) << i;
  }
  EXPECT_NEAR(fix.best_sq_norm, 1506.435789, 1e-4);
  EXPECT_NEAR(fix.second_sq_norm, 1612.811795, 1e-4);
  // Exact rational arithmetic (Python fractions, computed for this test) on
  // the double values of the published numbers, which is what the solver
  // sees: 1506.4358269522884 and 1612.811786287386. (On the decimal numbers
  // themselves: 1506.4358147 and 1612.8117665; the difference is the double
  // rounding of a_hat ~ 1e7 cycles, 1e-9 cycles, through a nearly singular Q,
  // L2 = 1.283 L1.) RTKLIB's printed values are 4e-5 and 9e-6 from these.
  EXPECT_NEAR(fix.best_sq_norm, 1506.4358269522884, 1e-9 * 1506.4);
  EXPECT_NEAR(fix.second_sq_norm, 1612.811786287386, 1e-9 * 1612.8);
  EXPECT_FALSE(fix.fixed);  // ratio 1.07
  std::printf("RTKLIB utest2: norms %.10f %.10f (RTKLIB 1506.435789 1612.811795), %u reduction passes, "
              "%u permutations, %u search steps\n",
              fix.best_sq_norm, fix.second_sq_norm, fix.reduction_steps, fix.permutations, fix.search_steps);
}

// The 3-D example of de Jonge & Tiberius 1996 (LGR-Series 12, sections 3.8 and
// 4.12; also in Joosten & Tiberius, "LAMBDA: FAQs"). Numbers from two
// recodings: Q, a_hat and the true integers (5, 3, 4) from Kai Borre's MATLAB
// driver call_lam.m ("3D-example of sections 3.8 and 4.12"); the best and
// second best with their squared norms from Orekit's test, repository
// CS-SI/Orekit, file src/test/java/org/orekit/estimation/measurements/gnss/
// AbstractLambdaMethodTest.java, testJoostenTiberiusFAQ (checked there to 1e-15).
const LambdaVec kDjtFloat = vec_of({5.45, 3.10, 2.97});
const LambdaMat kDjtCov = mat_of(3, {6.290, 5.978, 0.544, 5.978, 6.292, 2.340, 0.544, 2.340, 6.288});

TEST(LambdaPublishedExample, DeJongeTiberius3dExampleGivesPublishedBestAndSecond) {
  LambdaSolver solver;
  LambdaFix fix;
  ASSERT_EQ(solver.solve(kDjtFloat, kDjtCov, 3, fix), Status::kOk);
  EXPECT_EQ(fix.best_cyc(0), 5.0);
  EXPECT_EQ(fix.best_cyc(1), 3.0);
  EXPECT_EQ(fix.best_cyc(2), 4.0);
  EXPECT_EQ(fix.second_cyc(0), 6.0);
  EXPECT_EQ(fix.second_cyc(1), 4.0);
  EXPECT_EQ(fix.second_cyc(2), 4.0);
  EXPECT_NEAR(fix.best_sq_norm, 0.2183310953369383, 1e-12);
  EXPECT_NEAR(fix.second_sq_norm, 0.3072725757902666, 1e-12);
  EXPECT_NEAR(fix.ratio, 0.3072725757902666 / 0.2183310953369383, 1e-12);
  EXPECT_FALSE(fix.fixed);  // 1.41: the example's float solution is far from unique
}

// ---------------------------------------------------------------------------
// Exhaustive enumeration. The box: every integer a with
// (a_hat - a)^T Q^-1 (a_hat - a) <= chi2 has |a_i - a_hat_i| <= sqrt(chi2 Q_ii)
// (the ellipsoid's extent along axis i). chi2 = the direct norm of the second
// vector LAMBDA returned, an upper bound of the true second-best norm whatever
// LAMBDA got wrong (it is a real integer vector distinct from the best), so
// the box holds the true two best.

struct Ranked {
  LambdaVec a = LambdaVec::Zero();
  double norm = std::numeric_limits<double>::infinity();
};

// Two best over the box; returns false when the box has more than max_points.
bool enumerate_two_best(const LambdaVec& a_hat, const LambdaMat& q, int n, double chi2, long max_points,
                        Ranked& first, Ranked& second, long& points) {
  const Eigen::LLT<LambdaMat> llt(padded(q, n));
  const LambdaMat q_inv = llt.solve(LambdaMat::Identity());
  LambdaVec lo = LambdaVec::Zero();
  LambdaVec hi = LambdaVec::Zero();
  points = 1;
  for (int i = 0; i < n; ++i) {
    const double w = std::sqrt(chi2 * q(i, i)) * (1.0 + 1e-9) + 1e-9;
    lo(i) = std::ceil(a_hat(i) - w);
    hi(i) = std::floor(a_hat(i) + w);
    points *= static_cast<long>(hi(i) - lo(i) + 1.0);
    if (points > max_points) return false;
  }
  LambdaVec a = lo;
  for (;;) {
    LambdaVec r = LambdaVec::Zero();
    for (int i = 0; i < n; ++i) r(i) = a_hat(i) - a(i);
    double norm = 0.0;
    for (int i = 0; i < n; ++i) {
      double row = 0.0;
      for (int j = 0; j < n; ++j) row += q_inv(i, j) * r(j);
      norm += r(i) * row;
    }
    if (norm < second.norm) {
      if (norm < first.norm) {
        second = first;
        first.a = a;
        first.norm = norm;
      } else {
        second.a = a;
        second.norm = norm;
      }
    }
    int i = 0;
    while (i < n && a(i) >= hi(i)) {
      a(i) = lo(i);
      ++i;
    }
    if (i == n) break;
    a(i) += 1.0;
  }
  // Exact norms of the two (the inverse above only ranks).
  first.norm = direct_sq_norm(a_hat, q, n, first.a);
  second.norm = direct_sq_norm(a_hat, q, n, second.a);
  return true;
}

TEST(LambdaBruteForce, TwoBestEqualExhaustiveEnumerationOnRandomCorrelatedProblems) {
  std::mt19937_64 rng(20240516);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0;
  int skipped = 0;
  int high_cond = 0;
  long max_points = 0;
  double worst_rel = 0.0;  // largest relative norm difference LAMBDA vs direct
  for (int n = 2; n <= 5; ++n) {
    for (int trial = 0; trial < 150; ++trial) {
      const double cond = std::pow(10.0, 6.0 * unit(rng));        // 1 .. 1e6
      const double lambda_max = std::pow(10.0, -2.0 + 2.0 * unit(rng));  // 0.01 .. 1 cycles^2
      const LambdaMat q = random_spd(rng, n, lambda_max, cond);
      LambdaVec a_hat = LambdaVec::Zero();
      for (int i = 0; i < n; ++i) a_hat(i) = 200.0 * (unit(rng) - 0.5);
      LambdaSolver solver;
      LambdaFix fix;
      ASSERT_EQ(solver.solve(a_hat, q, n, fix), Status::kOk) << "n " << n << " trial " << trial;
      const double best_direct = direct_sq_norm(a_hat, q, n, fix.best_cyc);
      const double second_direct = direct_sq_norm(a_hat, q, n, fix.second_cyc);
      worst_rel = std::max(worst_rel, std::fabs(fix.second_sq_norm - second_direct) / second_direct);
      if (best_direct > 1e-3) worst_rel = std::max(worst_rel, std::fabs(fix.best_sq_norm - best_direct) / best_direct);
      // The reported norms are those of the reported vectors.
      ASSERT_NEAR(fix.best_sq_norm, best_direct, 1e-9 * best_direct + 1e-12) << "n " << n << " trial " << trial;
      ASSERT_NEAR(fix.second_sq_norm, second_direct, 1e-9 * second_direct) << "n " << n << " trial " << trial;
      ASSERT_GT((fix.best_cyc - fix.second_cyc).cwiseAbs().maxCoeff(), 0.5) << "two distinct vectors";
      Ranked first;
      Ranked second;
      long points = 0;
      if (!enumerate_two_best(a_hat, q, n, second_direct, 20000000, first, second, points)) {
        ++skipped;
        continue;
      }
      ++checked;
      if (cond > 1e5) ++high_cond;
      max_points = std::max(max_points, points);
      for (int i = 0; i < n; ++i) {
        ASSERT_EQ(fix.best_cyc(i), first.a(i)) << "n " << n << " trial " << trial << " cond " << cond;
        ASSERT_EQ(fix.second_cyc(i), second.a(i)) << "n " << n << " trial " << trial << " cond " << cond;
      }
      EXPECT_NEAR(fix.best_sq_norm, first.norm, 1e-9 * first.norm + 1e-12);
      EXPECT_NEAR(fix.second_sq_norm, second.norm, 1e-9 * second.norm);
    }
  }
  std::printf("brute force: %d problems checked (%d with condition number > 1e5), %d skipped (box > 2e7 points), "
              "largest box %ld points, largest relative norm difference to the direct evaluation %.2g\n",
              checked, high_cond, skipped, max_points, worst_rel);
  EXPECT_GE(checked, 540);  // of 600
  EXPECT_GE(high_cond, 40);
}

// Integer shifts of a_hat move the solution by the same integers and leave the
// norms: also checks the exactness of the integer bookkeeping at 1e9 cycles
// (a_hat dyadic, so a_hat + shift is exact in double).
TEST(LambdaBruteForce, IntegerShiftOfTheFloatShiftsTheSolutionExactly) {
  const LambdaVec a_hat = vec_of({5.375, 3.125, 2.96875});
  const LambdaVec shift = vec_of({989457273.0, -6716599.0, 1234567890123.0});
  LambdaSolver solver;
  LambdaFix base;
  LambdaFix moved;
  ASSERT_EQ(solver.solve(a_hat, kDjtCov, 3, base), Status::kOk);
  ASSERT_EQ(solver.solve(a_hat + shift, kDjtCov, 3, moved), Status::kOk);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(moved.best_cyc(i), base.best_cyc(i) + shift(i));
    EXPECT_EQ(moved.second_cyc(i), base.second_cyc(i) + shift(i));
  }
  EXPECT_EQ(moved.best_sq_norm, base.best_sq_norm);
  EXPECT_EQ(moved.second_sq_norm, base.second_sq_norm);
}

// ---------------------------------------------------------------------------
// Decorrelation.

// Checks the solver's Z, L, D after a solve of (q, n).
void expect_valid_decorrelation(const LambdaSolver& solver, const LambdaMat& q, int n, const char* what) {
  SCOPED_TRACE(what);
  const LambdaMat& z = solver.transform();
  const LambdaMat& z_inv = solver.transform_inverse();
  const LambdaMat& l = solver.factor_l();
  const LambdaVec& d = solver.factor_d();
  ASSERT_EQ(solver.size(), n);
  // Z and Z^-1 integer and Z Z^-1 = I exactly: det Z and det Z^-1 are
  // integers with product 1, so |det Z| = 1 (unimodular). Also the determinant itself.
  LambdaMat zp = LambdaMat::Identity();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      ASSERT_EQ(z(i, j), std::round(z(i, j)));
      ASSERT_EQ(z_inv(i, j), std::round(z_inv(i, j)));
      double s = 0.0;
      for (int k = 0; k < n; ++k) s += z(i, k) * z_inv(k, j);
      ASSERT_EQ(s, i == j ? 1.0 : 0.0) << i << "," << j;
      zp(i, j) = z(i, j);
    }
  }
  EXPECT_NEAR(std::fabs(Eigen::FullPivLU<LambdaMat>(zp).determinant()), 1.0, 1e-6);
  // Z^T Q Z = L^T D L (the factorisation of the decorrelated covariance).
  double worst = 0.0;
  double scale = 0.0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      double zqz = 0.0;
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) zqz += z(a, i) * q(a, b) * z(b, j);
      }
      double ltdl = 0.0;
      for (int k = std::max(i, j); k < n; ++k) ltdl += l(k, i) * d(k) * l(k, j);
      worst = std::max(worst, std::fabs(zqz - ltdl));
      scale = std::max(scale, std::fabs(zqz));
    }
  }
  EXPECT_LE(worst, 1e-9 * scale);
  // L unit lower triangular and size-reduced: |L_ij| <= 1/2 below the diagonal.
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(l(i, i), 1.0);
    for (int j = i + 1; j < n; ++j) EXPECT_EQ(l(i, j), 0.0);
    for (int j = 0; j < i; ++j) EXPECT_LE(std::fabs(l(i, j)), 0.5 + 1e-12) << i << "," << j;
  }
  // Ordered: no permutation of neighbours would shrink the later conditional
  // variance (d_k + L_{k+1,k}^2 d_{k+1} >= d_{k+1}, to the swap margin).
  for (int k = 0; k + 1 < n; ++k) {
    EXPECT_GE(d(k) + l(k + 1, k) * l(k + 1, k) * d(k + 1), (1.0 - 1e-6) * d(k + 1)) << k;
  }
  // det Q = prod d (Z unimodular), and the spread of the conditional
  // variances never grows: every permutation puts both new values between the
  // two old ones, Gauss transformations leave D alone.
  const LambdaVec d0 = conditional_variances(q, n);
  double log_det_before = 0.0;
  double log_det_after = 0.0;
  for (int i = 0; i < n; ++i) {
    log_det_before += std::log(d0(i));
    log_det_after += std::log(d(i));
  }
  EXPECT_NEAR(log_det_after, log_det_before, 1e-8 * n);
  EXPECT_LE(d.head(n).maxCoeff(), d0.head(n).maxCoeff() * (1.0 + 1e-9));
  EXPECT_GE(d.head(n).minCoeff(), d0.head(n).minCoeff() * (1.0 - 1e-9));
}

TEST(LambdaDecorrelation, ZIsUnimodularAndLdlIsReducedAndOrderedOnRandomProblems) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int n = 1; n <= kLambdaMaxAmb; ++n) {
    for (int trial = 0; trial < 20; ++trial) {
      const double cond = std::pow(10.0, 8.0 * unit(rng));
      const LambdaMat q = random_spd(rng, n, 1.0, cond);
      LambdaVec a_hat = LambdaVec::Zero();
      for (int i = 0; i < n; ++i) a_hat(i) = 50.0 * (unit(rng) - 0.5);
      LambdaSolver solver;
      LambdaFix fix;
      ASSERT_EQ(solver.solve(a_hat, q, n, fix), Status::kOk) << n << " " << trial;
      expect_valid_decorrelation(solver, q, n, "random");
      if (HasFailure()) return;
    }
  }
}

TEST(LambdaDecorrelation, DualFrequencyCovarianceIsStronglyDecorrelated) {
  // The shape of RTKLIB utest2 scaled to 16 ambiguities: L1 and L2 of one
  // satellite correlated 1 - 3e-4. The spread of the conditional variances
  // max(d)/min(d) must fall by orders of magnitude (the point of LAMBDA), and
  // the largest correlation coefficient of Z^T Q Z must be far from 1.
  std::mt19937_64 rng(3);
  LambdaMat q;
  LambdaVec a_hat;
  LambdaVec truth;
  gnss_like(rng, 16, q, a_hat, truth);
  LambdaSolver solver;
  LambdaFix fix;
  ASSERT_EQ(solver.solve(a_hat, q, 16, fix), Status::kOk);
  expect_valid_decorrelation(solver, q, 16, "dual frequency");
  const LambdaVec d0 = conditional_variances(q, 16);
  const LambdaVec& d = solver.factor_d();
  const double spread_before = d0.head(16).maxCoeff() / d0.head(16).minCoeff();
  const double spread_after = d.head(16).maxCoeff() / d.head(16).minCoeff();
  const LambdaMat qz = solver.transform().transpose() * q * solver.transform();
  double corr_before = 0.0;
  double corr_after = 0.0;
  for (int i = 0; i < 16; ++i) {
    for (int j = 0; j < i; ++j) {
      corr_before = std::max(corr_before, std::fabs(q(i, j)) / std::sqrt(q(i, i) * q(j, j)));
      corr_after = std::max(corr_after, std::fabs(qz(i, j)) / std::sqrt(qz(i, i) * qz(j, j)));
    }
  }
  std::printf("dual frequency n=16: spread of conditional variances %.3g -> %.3g, largest |correlation| %.6f -> %.3f\n",
              spread_before, spread_after, corr_before, corr_after);
  EXPECT_LT(spread_after, spread_before / 100.0);
  EXPECT_GT(corr_before, 0.999);
  EXPECT_LT(corr_after, 0.9);
}

TEST(LambdaDecorrelation, PublishedExamplesGiveValidDecorrelation) {
  LambdaSolver solver;
  LambdaFix fix;
  ASSERT_EQ(solver.solve(kDjtFloat, kDjtCov, 3, fix), Status::kOk);
  expect_valid_decorrelation(solver, kDjtCov, 3, "de Jonge & Tiberius 3-D");
}

// ---------------------------------------------------------------------------
// Refused inputs and small sizes.

TEST(LambdaInput, RefusesBadSizeNonFiniteInputSingularAndIndefiniteCovariance) {
  LambdaSolver solver;
  LambdaFix fix;
  const LambdaVec a = vec_of({0.3, -1.2, 4.4});
  const LambdaMat good = mat_of(2, {1.0, 0.5, 0.5, 1.0});
  ASSERT_EQ(solver.solve(a, good, 2, fix), Status::kOk);
  ASSERT_TRUE(fix.n == 2);

  auto expect_refused = [&](Status expected, const LambdaVec& av, const LambdaMat& qv, int n, double threshold,
                            const char* what) {
    LambdaFix f;
    f.fixed = true;
    EXPECT_EQ(solver.solve(av, qv, n, f, threshold), expected) << what;
    EXPECT_FALSE(f.fixed) << what;
    EXPECT_EQ(f.n, 0) << what;
    EXPECT_EQ(solver.size(), 0) << what;
  };
  expect_refused(Status::kInvalidArgument, a, good, 0, 3.0, "n = 0");
  expect_refused(Status::kInvalidArgument, a, good, -1, 3.0, "n < 0");
  expect_refused(Status::kInvalidArgument, LambdaVec::Zero(), LambdaMat::Identity(), kLambdaMaxAmb + 1, 3.0, "n > max");
  LambdaVec nan_a = a;
  nan_a(1) = std::numeric_limits<double>::quiet_NaN();
  expect_refused(Status::kInvalidArgument, nan_a, good, 2, 3.0, "NaN in a_hat");
  LambdaVec inf_a = a;
  inf_a(0) = std::numeric_limits<double>::infinity();
  expect_refused(Status::kInvalidArgument, inf_a, good, 2, 3.0, "Inf in a_hat");
  LambdaVec huge_a = a;
  huge_a(0) = 1e16;
  expect_refused(Status::kInvalidArgument, huge_a, good, 2, 3.0, "a_hat beyond 2^52 cycles");
  LambdaMat nan_q = good;
  nan_q(1, 0) = std::numeric_limits<double>::quiet_NaN();
  expect_refused(Status::kInvalidArgument, a, nan_q, 2, 3.0, "NaN in Q");
  expect_refused(Status::kInvalidArgument, a, good, 2, 0.5, "ratio threshold below 1");
  expect_refused(Status::kInvalidArgument, a, good, 2, std::numeric_limits<double>::quiet_NaN(), "NaN threshold");

  expect_refused(kLambdaNotPositiveDefinite, a, mat_of(2, {1.0, 1.0, 1.0, 1.0}), 2, 3.0, "singular");
  expect_refused(kLambdaNotPositiveDefinite, a, mat_of(2, {1.0, 2.0, 2.0, 1.0}), 2, 3.0, "indefinite");
  expect_refused(kLambdaNotPositiveDefinite, a, mat_of(2, {-1.0, 0.0, 0.0, 1.0}), 2, 3.0, "negative variance");
  expect_refused(kLambdaNotPositiveDefinite, a, LambdaMat::Zero(), 3, 3.0, "zero");
  // Numerically singular: rank 2 in 3-D up to rounding.
  expect_refused(kLambdaNotPositiveDefinite, a,
                 mat_of(3, {1.0, 0.3, 1.3, 0.3, 2.0, 2.3, 1.3, 2.3, 3.6}), 3, 3.0, "rank deficient");
  EXPECT_EQ(kLambdaNotPositiveDefinite, Status::kSingular);
  EXPECT_EQ(kLambdaSearchFailed, Status::kNotFound);

  // A refusal leaves the solver usable.
  ASSERT_EQ(solver.solve(kDjtFloat, kDjtCov, 3, fix), Status::kOk);
  EXPECT_NEAR(fix.best_sq_norm, 0.2183310953369383, 1e-12);
}

TEST(LambdaInput, ExceededStepCapsReportSearchFailed) {
  LambdaVec a;
  LambdaMat q;
  rtklib_utest2(a, q);
  LambdaSolver solver;
  LambdaFix fix;
  ASSERT_EQ(solver.solve(a, q, 10, fix), Status::kOk);
  const uint32_t reduction_needed = fix.reduction_steps;
  const uint32_t search_needed = fix.search_steps;
  ASSERT_GT(reduction_needed, 2U);
  ASSERT_GT(search_needed, 2U);

  solver.set_step_caps(reduction_needed - 1, 0);
  EXPECT_EQ(solver.solve(a, q, 10, fix), kLambdaSearchFailed);
  EXPECT_EQ(fix.reduction_steps, reduction_needed - 1);
  EXPECT_FALSE(fix.fixed);
  EXPECT_EQ(fix.n, 0);
  EXPECT_EQ(fix.best_sq_norm, 0.0);

  solver.set_step_caps(reduction_needed, search_needed - 1);
  EXPECT_EQ(solver.solve(a, q, 10, fix), kLambdaSearchFailed);
  EXPECT_EQ(fix.reduction_steps, reduction_needed);
  EXPECT_EQ(fix.search_steps, search_needed - 1);
  EXPECT_EQ(fix.n, 0);

  solver.set_step_caps(reduction_needed, search_needed);  // exactly enough
  EXPECT_EQ(solver.solve(a, q, 10, fix), Status::kOk);
  solver.set_step_caps(0, 0);  // back to the defaults
  EXPECT_EQ(solver.solve(a, q, 10, fix), Status::kOk);
  EXPECT_NEAR(fix.best_sq_norm, 1506.4358269522884, 1e-9 * 1506.4);
}

TEST(LambdaInput, OneAmbiguityRoundsAndTheSecondIsTheOtherNeighbour) {
  LambdaSolver solver;
  LambdaFix fix;
  LambdaMat q = LambdaMat::Zero();
  q(0, 0) = 0.04;  // 0.2 cycles 1-sigma
  ASSERT_EQ(solver.solve(vec_of({-7.3}), q, 1, fix), Status::kOk);
  EXPECT_EQ(fix.n, 1);
  EXPECT_EQ(fix.best_cyc(0), -7.0);
  EXPECT_EQ(fix.second_cyc(0), -8.0);
  EXPECT_NEAR(fix.best_sq_norm, 0.3 * 0.3 / 0.04, 1e-12);
  EXPECT_NEAR(fix.second_sq_norm, 0.7 * 0.7 / 0.04, 1e-12);
  EXPECT_NEAR(fix.ratio, 49.0 / 9.0, 1e-9);
  EXPECT_TRUE(fix.fixed);
  ASSERT_EQ(solver.solve(vec_of({2.6}), q, 1, fix), Status::kOk);
  EXPECT_EQ(fix.best_cyc(0), 3.0);
  EXPECT_EQ(fix.second_cyc(0), 2.0);
}

TEST(LambdaInput, ReusedSolverAnswersLikeAFreshOne) {
  // Scratch left by a large problem must not leak into a small one.
  std::mt19937_64 rng(11);
  LambdaMat q;
  LambdaVec a_hat;
  LambdaVec truth;
  gnss_like(rng, 16, q, a_hat, truth);
  LambdaSolver used;
  LambdaFix fix;
  ASSERT_EQ(used.solve(a_hat, q, 16, fix), Status::kOk);
  LambdaFix again;
  LambdaFix fresh;
  LambdaSolver fresh_solver;
  ASSERT_EQ(used.solve(kDjtFloat, kDjtCov, 3, again), Status::kOk);
  ASSERT_EQ(fresh_solver.solve(kDjtFloat, kDjtCov, 3, fresh), Status::kOk);
  EXPECT_TRUE(again.best_cyc == fresh.best_cyc);
  EXPECT_TRUE(again.second_cyc == fresh.second_cyc);
  EXPECT_EQ(again.best_sq_norm, fresh.best_sq_norm);
  EXPECT_EQ(again.second_sq_norm, fresh.second_sq_norm);
}

// ---------------------------------------------------------------------------
// Ratio test.

TEST(LambdaRatioTest, ClearlyUniqueBestIsFixedAndNearTieIsNot) {
  LambdaSolver solver;
  LambdaFix fix;
  const LambdaMat q = mat_of(3, {0.010, 0.004, 0.002, 0.004, 0.012, 0.003, 0.002, 0.003, 0.009});
  // 0.05 cycles from (12, -3, 7) with 0.1 cycles 1-sigma: unique.
  ASSERT_EQ(solver.solve(vec_of({12.05, -3.04, 6.97}), q, 3, fix), Status::kOk);
  EXPECT_EQ(fix.best_cyc(0), 12.0);
  EXPECT_EQ(fix.best_cyc(1), -3.0);
  EXPECT_EQ(fix.best_cyc(2), 7.0);
  EXPECT_GE(fix.ratio, 3.0);
  EXPECT_TRUE(fix.fixed);
  // Half way between two integers on the first ambiguity: a near tie.
  ASSERT_EQ(solver.solve(vec_of({12.49, -3.0, 7.0}), mat_of(3, {0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01}), 3, fix),
            Status::kOk);
  EXPECT_LT(fix.ratio, 1.2);
  EXPECT_GE(fix.ratio, 1.0);
  EXPECT_FALSE(fix.fixed);
}

TEST(LambdaRatioTest, ThresholdArgumentDecidesAndDefaultsToSeed002sThree) {
  EXPECT_EQ(kLambdaDefaultRatio, 3.0);
  LambdaSolver solver;
  LambdaFix fix;
  LambdaMat q = LambdaMat::Zero();
  q(0, 0) = 0.1;
  q(1, 1) = 0.1;
  // Best (1, 2) at 0.35^2/0.1, second (0, 2) at 0.65^2/0.1: ratio 3.449.
  const LambdaVec a = vec_of({0.65, 2.0});
  const double ratio = (0.65 * 0.65) / (0.35 * 0.35);
  ASSERT_EQ(solver.solve(a, q, 2, fix, 3.5), Status::kOk);
  EXPECT_FALSE(fix.fixed);
  ASSERT_EQ(solver.solve(a, q, 2, fix), Status::kOk);
  EXPECT_NEAR(fix.ratio, ratio, 1e-12);
  EXPECT_TRUE(fix.fixed);
  const double exact = fix.ratio;
  ASSERT_EQ(solver.solve(a, q, 2, fix, exact), Status::kOk);
  EXPECT_TRUE(fix.fixed);  // ratio >= threshold: equality fixes
  ASSERT_EQ(solver.solve(a, q, 2, fix, std::nextafter(exact, 4.0)), Status::kOk);
  EXPECT_FALSE(fix.fixed);
}

TEST(LambdaRatioTest, FloatOnAnIntegerGivesTheLargeFiniteRatioAndFixes) {
  LambdaSolver solver;
  LambdaFix fix;
  ASSERT_EQ(solver.solve(vec_of({4.0, -2.0, 9.0}), kDjtCov, 3, fix), Status::kOk);
  EXPECT_EQ(fix.best_sq_norm, 0.0);
  EXPECT_GT(fix.second_sq_norm, 0.0);
  EXPECT_EQ(fix.ratio, kLambdaMaxRatio);
  EXPECT_TRUE(std::isfinite(fix.ratio));
  EXPECT_TRUE(fix.fixed);
  EXPECT_EQ(fix.best_cyc(0), 4.0);
  EXPECT_EQ(fix.best_cyc(1), -2.0);
  EXPECT_EQ(fix.best_cyc(2), 9.0);
}

// ---------------------------------------------------------------------------
// Cost per solve on this host (printed for docs/lambda.md; no timed assertion)
// and the iteration counts behind kLambdaMaxReductionSteps / kLambdaMaxSearchSteps.

TEST(LambdaCost, PrintsSolveTimeAndIterationCountsForEightAndSixteenAmbiguities) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int kind = 0; kind < 2; ++kind) {
    for (int n : {8, 16}) {
      constexpr int kProblems = 200;
      constexpr int kRepeats = 10;
      std::vector<LambdaMat> qs(kProblems);
      std::vector<LambdaVec> as(kProblems);
      std::vector<LambdaVec> truths(kProblems);
      for (int p = 0; p < kProblems; ++p) {
        if (kind == 0) {
          gnss_like(rng, n, qs[p], as[p], truths[p]);
        } else {
          qs[p] = random_spd(rng, n, 1.0, std::pow(10.0, 6.0 * unit(rng)));
          as[p].setZero();
          for (int i = 0; i < n; ++i) as[p](i) = 1e4 * (unit(rng) - 0.5);
          truths[p].setConstant(std::numeric_limits<double>::quiet_NaN());
        }
      }
      LambdaSolver solver;
      LambdaFix fix;
      uint32_t max_red = 0;
      uint32_t max_search = 0;
      double sum_search = 0.0;
      int correct = 0;
      int fixed = 0;
      double worst_us = 0.0;
      const auto t0 = std::chrono::steady_clock::now();
      for (int r = 0; r < kRepeats; ++r) {
        for (int p = 0; p < kProblems; ++p) {
          const auto s0 = std::chrono::steady_clock::now();
          const Status s = solver.solve(as[p], qs[p], n, fix);
          const auto s1 = std::chrono::steady_clock::now();
          worst_us = std::max(worst_us, std::chrono::duration<double, std::micro>(s1 - s0).count());
          ASSERT_EQ(s, Status::kOk);
          if (r == 0) {
            max_red = std::max(max_red, fix.reduction_steps);
            max_search = std::max(max_search, fix.search_steps);
            sum_search += fix.search_steps;
            fixed += fix.fixed ? 1 : 0;
            bool ok_fix = kind == 0;
            for (int i = 0; i < n && ok_fix; ++i) ok_fix = fix.best_cyc(i) == truths[p](i);
            correct += ok_fix ? 1 : 0;
          }
        }
      }
      const auto t1 = std::chrono::steady_clock::now();
      const double mean_us = std::chrono::duration<double, std::micro>(t1 - t0).count() / (kProblems * kRepeats);
      std::printf("LAMBDA cost %s n=%2d: %.1f us per solve (worst %.1f us), reduction passes max %u, "
                  "search steps mean %.0f max %u, fixed at ratio 3: %d/%d%s\n",
                  kind == 0 ? "gnss-like   " : "random cond<=1e6", n, mean_us, worst_us, max_red, sum_search / kProblems,
                  max_search, fixed, kProblems, kind == 0 ? "" : " (no truth)");
      if (kind == 0) std::printf("  best == truth: %d/%d\n", correct, kProblems);
      EXPECT_LT(max_red, kLambdaMaxReductionSteps / 10);
      EXPECT_LT(max_search, kLambdaMaxSearchSteps / 10);
    }
  }
}

}  // namespace
}  // namespace uwbnav
