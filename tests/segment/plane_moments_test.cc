// The plane fits from moment sums: the 3x3 smallest-eigenpair solver against Eigen's
// SelfAdjointEigenSolver on seeded random symmetric positive semi-definite matrices (plane-like,
// near-degenerate and degenerate spectra), and FitPlane on points of known planes.

#include "segment/plane_moments.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

namespace hgrasp::segment {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

Sym3 ToSym3(const Matrix3d& a) { return {a(0, 0), a(0, 1), a(0, 2), a(1, 1), a(1, 2), a(2, 2)}; }

// Q diag(l) Q^T for a random rotation Q.
Matrix3d WithEigenvalues(const Vector3d& l, std::mt19937* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Quaterniond q = Eigen::Quaterniond(g(*rng), g(*rng), g(*rng), g(*rng)).normalized();
  const Matrix3d r = q.toRotationMatrix();
  const Matrix3d a = r * l.asDiagonal() * r.transpose();
  return 0.5 * (a + a.transpose());
}

// Random spectra: (largest, middle, smallest) as fractions of a scale, by kind.
Vector3d Spectrum(int kind, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double scale = std::pow(10.0, -6.0 + 4.0 * u(*rng));  // 1e-6 .. 1e-2 m^2
  const double a = scale, b = scale * (0.05 + 0.95 * u(*rng));
  switch (kind) {
    case 0:  // general
      return {a, b, b * u(*rng)};
    case 1:  // plane-like: smallest far below the others
      return {a, b, b * std::pow(10.0, -10.0 * u(*rng) - 2.0)};
    case 2:  // near-double smallest
      return {a, b, b * (1.0 - 1e-9 * u(*rng))};
    case 3:  // exactly double smallest
      return {a, b, b};
    case 4:  // near-double largest
      return {a, a * (1.0 - 1e-9 * u(*rng)), b * 0.5};
    case 5:  // all three (nearly) equal
      return {a, a * (1.0 - 1e-12 * u(*rng)), a * (1.0 - 2e-12 * u(*rng))};
    default:  // rank deficient: a line or a point set
      return {a, u(*rng) < 0.5 ? b : 0.0, 0.0};
  }
}

// Accuracy bounds per kind of spectrum, as fractions of the largest eigenvalue: the eigenvalue
// from 0, from a lower bound (half the value, as MergeRegions starts from one), and the
// eigenvector's |A v - lambda v|. Measured over 20000 matrices of each kind: 3.7e-10, 4.9e-10,
// 3e-10 (general: some have a near-double smallest root); about 1e-15 for the plane-like, the
// near-double largest and the rank-deficient ones; near a double or triple smallest root the
// polynomial's root is ill-conditioned and Halley's convergence only linear, so the stop test
// (made for cubic convergence) ends early: 2.8e-6, 4.1e-4 (!), 6.4e-7 for a near-double,
// 1.5e-6, 1.4e-6, 3.4e-7 for an exact double and 1.1e-5, 1.1e-5, 2e-12 for a near-triple.
struct Bounds {
  double eigenvalue, from_bound, eigenvector;
};
constexpr Bounds kBounds[7] = {
    {1e-8, 1e-8, 1e-8},    {1e-14, 1e-14, 1e-14}, {1e-5, 2e-3, 5e-6},    {1e-5, 1e-5, 5e-6},
    {1e-14, 1e-14, 1e-14}, {1e-4, 1e-4, 1e-11},   {1e-14, 1e-14, 1e-14},
};

TEST(SmallestEigenvalue, MatchesEigenOnRandomPsdMatrices) {
  std::mt19937 rng(20261207);
  int checked = 0;
  for (int kind = 0; kind <= 6; ++kind) {
    const Bounds& tol = kBounds[kind];
    for (int trial = 0; trial < 2000; ++trial) {
      const Matrix3d a = WithEigenvalues(Spectrum(kind, &rng), &rng);
      const Eigen::SelfAdjointEigenSolver<Matrix3d> es(a);
      const double lmax = es.eigenvalues()(2);
      const double expected = std::max(0.0, es.eigenvalues()(0));
      const double lambda = SmallestEigenvalue(ToSym3(a));
      ASSERT_NEAR(lambda, expected, tol.eigenvalue * lmax) << "kind " << kind << " #" << trial;
      ASSERT_GE(lambda, 0.0);
      ASSERT_NEAR(SmallestEigenvalue(ToSym3(a), 0.5 * expected), expected, tol.from_bound * lmax)
          << "kind " << kind << " #" << trial;

      const Vector3d v = SmallestEigenvector(ToSym3(a), lambda);
      ASSERT_NEAR(v.norm(), 1.0, 1e-12);
      // An eigenvector of the smallest eigenvalue: A v = lambda v; where that eigenvalue is
      // simple with a gap, Eigen's up to sign.
      EXPECT_LT((a * v - expected * v).norm(), tol.eigenvector * lmax) << "kind " << kind;
      const double gap = es.eigenvalues()(1) - es.eigenvalues()(0);
      if (gap > 1e-3 * lmax) {
        EXPECT_GT(std::abs(v.dot(es.eigenvectors().col(0))), 1.0 - 1e-9) << "kind " << kind;
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, 7 * 2000);
}

TEST(SmallestEigenvalue, StopsAboveTheLimit) {
  const Matrix3d a = Vector3d(3.0, 2.0, 1.0).asDiagonal();
  EXPECT_NEAR(SmallestEigenvalue(ToSym3(a)), 1.0, 1e-15);
  // The iterates rise to the root from below: one above 0.5 is returned as it appears.
  EXPECT_GT(SmallestEigenvalue(ToSym3(a), 0.0, 0.5), 0.5);
  EXPECT_NEAR(SmallestEigenvalue(ToSym3(a), 0.0, 1.5), 1.0, 1e-15);
}

TEST(SmallestEigenvector, HandWorkedDiagonalAndDouble) {
  const Matrix3d a = Vector3d(2.0, 0.5, 1.0).asDiagonal();
  const Vector3d v = SmallestEigenvector(ToSym3(a), 0.5);
  EXPECT_NEAR(std::abs(v.y()), 1.0, 1e-15);
  // A double smallest eigenvalue (0.5, 0.5): any unit vector of the y-z plane.
  const Matrix3d d = Vector3d(2.0, 0.5, 0.5).asDiagonal();
  const Vector3d w = SmallestEigenvector(ToSym3(d), 0.5);
  EXPECT_NEAR(w.norm(), 1.0, 1e-15);
  EXPECT_NEAR(w.x(), 0.0, 1e-15);
}

TEST(Moments, SumsMeanAndCovarianceOfPoints) {
  const std::vector<Vector3d> pts = {{0, 0, 0}, {2, 0, 0}, {0, 4, 0}, {2, 4, 6}};
  Moments m;
  for (const Vector3d& p : pts) m.Add(p);
  EXPECT_EQ(m.n(), 4.0);
  EXPECT_EQ(m.Mean(), Vector3d(1, 2, 1.5));
  // Hand-worked: var x = 1, var y = 4, var z = 6.75, cov xy = 0, cov xz = 1.5, cov yz = 3.
  const Sym3 c = Covariance(m.v.data(), 1.0 / m.n());
  const Sym3 expected = {1.0, 0.0, 1.5, 4.0, 3.0, 6.75};
  for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(c[k], expected[k]) << k;
  Moments two;
  two.Add(pts[0]);
  two.Add(pts[1]);
  Moments joined = two;
  Moments rest;
  rest.Add(pts[2]);
  rest.Add(pts[3]);
  joined.Add(rest);
  EXPECT_EQ(joined.v, m.v);
  m.Remove(pts[3]);
  m.Remove(pts[2]);
  EXPECT_EQ(m.v, two.v);
}

TEST(Residual, ZeroForAtMostThreePoints) {
  Moments m;
  m.Add(Vector3d(0, 0, 0));
  m.Add(Vector3d(1, 0, 0));
  m.Add(Vector3d(0, 1, 5));
  EXPECT_EQ(Residual(m), 0.0);
  m.Add(Vector3d(1, 1, 0));  // off the plane of the first three: mean squared distance > 0
  EXPECT_GT(Residual(m), 0.05);
}

TEST(Orient, FollowsPlaneRegionsConvention) {
  EXPECT_EQ(Orient(Vector3d(0, 0, -1)), Vector3d(0, 0, 1));
  EXPECT_EQ(Orient(Vector3d(0.6, 0, 0.8)), Vector3d(0.6, 0, 0.8));       // horizontal enough
  EXPECT_EQ(Orient(Vector3d(0.8, 0, 0.6)), Vector3d(-0.8, -0.0, -0.6));  // faces the robot
  EXPECT_EQ(Orient(Vector3d(-0.8, 0, -0.6)), Vector3d(-0.8, 0, -0.6));
  EXPECT_EQ(Orient(Vector3d(0, 1, 0)), Vector3d(0, -1, 0));  // tie at x == 0: y <= 0
}

TEST(FitPlane, RecoversAKnownPlane) {
  // z = 0.3 x - 0.2 y + 0.1 on a 4 x 4 grid; normal (-0.3, 0.2, 1) / |.|.
  const Vector3d n = Vector3d(-0.3, 0.2, 1.0).normalized();
  Moments on, off;
  const double d = 1e-3;  // off: alternately +-d along n (checkerboard: uncorrelated with x, y)
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double x = 0.01 * i, y = 0.01 * j;
      const Vector3d p(x, y, 0.3 * x - 0.2 * y + 0.1);
      on.Add(p);
      off.Add(p + ((i + j) % 2 == 0 ? d : -d) * n);
    }
  }
  Vector3d normal;
  double residual;
  FitPlane(on, &normal, &residual);
  EXPECT_LT((normal - n).norm(), 1e-9);
  EXPECT_NEAR(residual, 0.0, 1e-15);
  FitPlane(off, &normal, &residual);
  EXPECT_LT((normal - n).norm(), 1e-9);
  EXPECT_NEAR(residual, d * d, 1e-15);
  EXPECT_NEAR(Residual(off), d * d, 1e-15);
}

}  // namespace
}  // namespace hgrasp::segment
