#include "segment/plane_moments.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace hgrasp::segment {
namespace {

/// Whether a Halley step `step` (from the left of the smallest root of x^3 - c2 x^2 + c1 x - c0,
/// to x, where the derivative is dp) leaves x within 1e-15 x of the root: the next error is
/// about |step|^3 |p''^2 / (4 p'^2) - p''' / (6 p')|, with |p''| <= 2 c2 there and p''' = 6.
bool Converged(double c2, double dp, double step, double x) {
  const double s = std::abs(step);
  return (c2 * c2 + dp) * s * s * s <= 1e-15 * x * dp * dp;
}

}  // namespace

Eigen::Matrix3d FullMatrix(const Sym3& m) {
  Eigen::Matrix3d a;
  a << m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5];
  return a;
}

double SmallestEigenvalue(const Sym3& m, double start, double stop_above) {
  const double a = m[0], d = m[1], f = m[2], b = m[3], e = m[4], c = m[5];
  // det(x I - m) = x^3 - c2 x^2 + c1 x - c0.
  const double c2 = a + b + c;
  const double c1 = a * b - d * d + a * c - f * f + b * c - e * e;
  const double c0 = a * (b * c - e * e) - d * (d * c - e * f) + f * (d * e - b * f);
  if (!(c0 > 0.0)) return 0.0;  // a zero (or, by rounding, negative) eigenvalue
  double x = std::max(0.0, start);
  for (int k = 0; k < 100; ++k) {
    const double p = ((x - c2) * x + c1) * x - c0;
    const double dp = (3.0 * x - 2.0 * c2) * x + c1;
    const double den = 2.0 * dp * dp - p * (6.0 * x - 2.0 * c2);
    if (!(dp > 0.0 && den > 0.0)) break;  // past the smallest root or at a double one
    const double step = 2.0 * p * dp / den;
    x -= step;
    if (x > stop_above) return x;
    if (Converged(c2, dp, step, x)) return std::max(0.0, x);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(FullMatrix(m), Eigen::EigenvaluesOnly);
  return std::max(0.0, es.eigenvalues()(0));
}

Eigen::Vector3d SmallestEigenvector(const Sym3& m, double lambda) {
  const Eigen::Vector3d r0(m[0] - lambda, m[1], m[2]);
  const Eigen::Vector3d r1(m[1], m[3] - lambda, m[4]);
  const Eigen::Vector3d r2(m[2], m[4], m[5] - lambda);
  const Eigen::Vector3d c[3] = {r0.cross(r1), r0.cross(r2), r1.cross(r2)};
  const double n2[3] = {c[0].squaredNorm(), c[1].squaredNorm(), c[2].squaredNorm()};
  const int k = n2[0] >= n2[1] ? (n2[0] >= n2[2] ? 0 : 2) : (n2[1] >= n2[2] ? 1 : 2);
  const double scale = std::max({r0.squaredNorm(), r1.squaredNorm(), r2.squaredNorm()});
  if (n2[k] > 1e-20 * scale * scale) return c[k] / std::sqrt(n2[k]);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(FullMatrix(m));
  return es.eigenvectors().col(0).normalized();
}

double Residual(const Moments& m, double start) {
  if (m.n() <= 3.0) return 0.0;
  return SmallestEigenvalue(Covariance(m.v.data(), 1.0 / m.n()), start);
}

Eigen::Vector3d Orient(Eigen::Vector3d n) {
  constexpr double kHorizontal = 0.70710678118654752;
  bool flip;
  if (std::abs(n.z()) >= kHorizontal) {
    flip = n.z() < 0.0;
  } else if (n.x() != 0.0) {
    flip = n.x() > 0.0;
  } else {
    flip = n.y() > 0.0;
  }
  return flip ? Eigen::Vector3d(-n) : n;
}

void FitPlane(const Moments& m, Eigen::Vector3d* normal, double* residual) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(
      FullMatrix(Covariance(m.v.data(), 1.0 / m.n())));
  *normal = Orient(es.eigenvectors().col(0).normalized());
  *residual = std::max(0.0, es.eigenvalues()(0));
}

}  // namespace hgrasp::segment
