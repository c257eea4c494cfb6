#pragma once
/// @file Plane fits from moment sums, shared by every stage of the segmentation: the moment sums of
/// a point set (O(1) to add a point or another set), their covariance, its smallest eigenvalue
/// (the plane fit's residual: the mean squared distance to the fitted plane, m^2) and eigenvector
/// (the plane's normal), and the orientation convention of PlaneRegion::normal_W.

#include <Eigen/Core>
#include <array>
#include <limits>

namespace hgrasp::segment {

/// A symmetric 3x3 matrix by its upper triangle: xx, xy, xz, yy, yz, zz.
using Sym3 = std::array<double, 6>;

/// Moment sums of a point set, relative to a common reference point to limit cancellation:
/// v = n, sum x, sum y, sum z, then sum p p^T's upper triangle (xx, xy, xz, yy, yz, zz).
struct Moments {
  std::array<double, 10> v{};

  void Add(const Eigen::Vector3d& p) {
    const double x = p.x(), y = p.y(), z = p.z();
    const std::array<double, 10> q = {1.0, x, y, z, x * x, x * y, x * z, y * y, y * z, z * z};
    for (int k = 0; k < 10; ++k) v[k] += q[k];
  }
  void Add(const Moments& o) {
    for (int k = 0; k < 10; ++k) v[k] += o.v[k];
  }
  void Remove(const Eigen::Vector3d& p) {
    const double x = p.x(), y = p.y(), z = p.z();
    const std::array<double, 10> q = {1.0, x, y, z, x * x, x * y, x * z, y * y, y * z, z * z};
    for (int k = 0; k < 10; ++k) v[k] -= q[k];
  }
  double n() const { return v[0]; }
  Eigen::Vector3d Mean() const { return Eigen::Vector3d(v[1], v[2], v[3]) / v[0]; }
};

/// Covariance (upper triangle) of the points whose moment sums are v (layout of Moments::v); w:
/// 1 / v[0].
inline Sym3 Covariance(const double* v, double w) {
  const double mx = v[1] * w, my = v[2] * w, mz = v[3] * w;
  return {v[4] * w - mx * mx, v[5] * w - mx * my, v[6] * w - mx * mz,
          v[7] * w - my * my, v[8] * w - my * mz, v[9] * w - mz * mz};
}

/// The full matrix of m.
Eigen::Matrix3d FullMatrix(const Sym3& m);

/// Smallest eigenvalue of a symmetric positive semi-definite (up to rounding) matrix, clamped at
/// 0, by Halley's method on the characteristic polynomial from `start`, which must not exceed
/// it (0 always qualifies; a lower bound near it saves steps): the polynomial's roots are all
/// real, so from the left of the smallest one the iterates rise to it, cubically for a plane-like
/// point set (smallest eigenvalue far below the others), and no trigonometric function is needed
/// (unlike the closed form). Falls back on Eigen's solver when the iteration stalls (a double
/// root). Returns a value above `stop_above` as soon as an iterate exceeds it.
double SmallestEigenvalue(const Sym3& m, double start = 0.0,
                          double stop_above = std::numeric_limits<double>::infinity());

/// Unit eigenvector of m for its smallest eigenvalue lambda (up to sign): the largest cross
/// product of two rows of m - lambda I, which span the other eigenvectors; Eigen's solver where
/// those rows are (nearly) parallel, i.e. the smallest eigenvalue is not simple.
Eigen::Vector3d SmallestEigenvector(const Sym3& m, double lambda);

/// Smallest eigenvalue of a moment set's covariance (m^2); 0 for at most 3 points (which always
/// lie in a plane). `start`: a lower bound (see SmallestEigenvalue).
double Residual(const Moments& m, double start = 0.0);

/// Orients a unit normal after PlaneRegion::normal_W's convention: n.z >= 0 where |n.z| >=
/// cos 45 deg, else n.x <= 0 (ties at n.x == 0: n.y <= 0).
Eigen::Vector3d Orient(Eigen::Vector3d n);

/// Plane fit of a moment set (at least one point): unit normal (oriented) and smallest
/// eigenvalue, by Eigen's iterative solver (for the few regions, where accuracy matters more than
/// time).
void FitPlane(const Moments& m, Eigen::Vector3d* normal, double* residual);

}  // namespace hgrasp::segment
