#include "scan/laser_self_calibration.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "common/error.h"

namespace hgrasp::scan {

std::optional<LaserCoefficients> FitCoefficients(const std::vector<Eigen::Vector3d>& pairs,
                                                 double f, double* rms_px) {
  std::vector<Eigen::Vector3d> kept = pairs;
  LaserCoefficients c;
  double rms = 0;
  constexpr int kPasses = 4;
  bool fitted = false;
  for (int pass = 0; pass < kPasses; ++pass) {
    if (kept.size() < 20) {
      if (!fitted) return std::nullopt;
      break;  // trimming left too few: keep the previous pass's fit
    }
    // Rows [xR, y, f] (alpha, beta, gamma) = -xL; columns scaled to unit size for conditioning.
    Eigen::MatrixXd A(kept.size(), 3);
    Eigen::VectorXd rhs(kept.size());
    for (size_t i = 0; i < kept.size(); ++i) {
      A.row(i) << kept[i].y(), kept[i].z(), f;
      rhs[i] = -kept[i].x();
    }
    const Eigen::Vector3d scale = A.colwise().norm().cwiseMax(1e-12);
    const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(As, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::Vector3d s = svd.singularValues();
    // Points on one line in space (a planar target) leave one direction undetermined.
    if (s[2] < 1e-4 * s[0]) return std::nullopt;
    const Eigen::Vector3d x = svd.solve(rhs).cwiseQuotient(scale);
    c = {x[0], x[1], x[2]};
    fitted = true;
    const Eigen::VectorXd r = A * x - rhs;
    rms = std::sqrt(r.squaredNorm() / r.size());
    if (pass == kPasses - 1) break;
    // Trim stray pairs (a candidate off the stripe, a stripe at an edge) and fit again.
    std::vector<Eigen::Vector3d> inliers;
    for (size_t i = 0; i < kept.size(); ++i) {
      if (std::abs(r[i]) <= std::max(2.5 * rms, 0.05)) inliers.push_back(kept[i]);
    }
    kept.swap(inliers);
  }
  if (rms_px != nullptr) *rms_px = rms;
  return c;
}

std::optional<LaserCoefficients> FitCoefficientsRobust(
    const std::vector<std::vector<Eigen::Vector3d>>& rows, double f, double inlier_px,
    std::vector<Eigen::Vector3d>* chosen, double* rms_px) {
  std::vector<const std::vector<Eigen::Vector3d>*> usable;
  for (const auto& r : rows)
    if (!r.empty()) usable.push_back(&r);
  if (usable.size() < 20) return std::nullopt;
  std::mt19937 rng(12345);
  std::uniform_int_distribution<size_t> pick_row(0, usable.size() - 1);
  auto select = [&](const LaserCoefficients& c, std::vector<Eigen::Vector3d>* out) {
    out->clear();
    for (const auto* r : usable) {
      const Eigen::Vector3d* best = nullptr;
      double best_r = inlier_px;
      for (const auto& p : *r) {
        const double res = std::abs(c.Residue(p.x(), p.y(), p.z(), f));
        if (res < best_r) best_r = res, best = &p;
      }
      if (best != nullptr) out->push_back(*best);
    }
  };
  LaserCoefficients best;
  size_t best_support = 0;
  std::vector<Eigen::Vector3d> support;
  for (int iter = 0; iter < 300; ++iter) {
    Eigen::Matrix3d A;
    Eigen::Vector3d b;
    for (int k = 0; k < 3; ++k) {
      const auto& r = *usable[pick_row(rng)];
      const Eigen::Vector3d& p = r[std::uniform_int_distribution<size_t>(0, r.size() - 1)(rng)];
      A.row(k) << p.y(), p.z(), f;
      b[k] = -p.x();
    }
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
    if (lu.rank() < 3) continue;
    const Eigen::Vector3d x = lu.solve(b);
    const LaserCoefficients c{x[0], x[1], x[2]};
    select(c, &support);
    if (support.size() > best_support) best_support = support.size(), best = c;
  }
  if (best_support < 20) return std::nullopt;
  select(best, chosen);
  const auto refined = FitCoefficients(*chosen, f, rms_px);
  if (refined) select(*refined, chosen);  // the refit's own inliers
  return refined;
}

robot::LaserCalibration FitRotatingPlane(
    const std::vector<std::pair<std::int32_t, Plane>>& planes_H) {
  HGRASP_DEMAND_MSG(planes_H.size() >= 3, "at least three encoder counts are needed");
  // Normals with one consistent sign.
  std::vector<std::int32_t> count;
  std::vector<Eigen::Vector3d> n;
  std::vector<double> d;
  for (const auto& [e, p] : planes_H) {
    const double sign = n.empty() || p.n.dot(n.front()) >= 0 ? 1.0 : -1.0;
    count.push_back(e);
    n.push_back(sign * p.n);
    d.push_back(sign * p.d);
  }
  // A first axis: the direction the normals are (nearly) perpendicular to. The cone a tilted
  // lens adds is left to the refinement on the stripe points.
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (const auto& v : n) S += v * v.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(S);
  Eigen::Vector3d axis = eig.eigenvectors().col(0);  // smallest eigenvalue
  // Angles of the normals about the axis, and their line against the count.
  auto fit_angles = [&](const Eigen::Vector3d& a, Eigen::Vector3d* e1, double* k, double* theta0) {
    *e1 = (n.front() - n.front().dot(a) * a).normalized();
    const Eigen::Vector3d e2 = a.cross(*e1);
    Eigen::MatrixXd A(n.size(), 2);
    Eigen::VectorXd theta(n.size());
    for (size_t i = 0; i < n.size(); ++i) {
      A.row(i) << count[i], 1.0;
      theta[i] = std::atan2(n[i].dot(e2), n[i].dot(*e1));
    }
    const Eigen::Vector2d x = A.colPivHouseholderQr().solve(theta);
    *k = x[0];
    *theta0 = x[1];
  };
  Eigen::Vector3d e1;
  double k = 0, theta0 = 0;
  fit_angles(axis, &e1, &k, &theta0);
  if (k < 0) {  // orient the axis so that the angle grows with the count
    axis = -axis;
    fit_angles(axis, &e1, &k, &theta0);
  }
  robot::LaserCalibration cal;
  cal.axis_H = axis;
  cal.rad_per_count = k;
  cal.normal0_H = std::cos(theta0) * e1 + std::sin(theta0) * axis.cross(e1);
  // Offsets: d_i = -m_i . p0 - delta with the model's normals m_i; p0 is held perpendicular to
  // the axis (a point anywhere on the axis serves).
  Eigen::MatrixXd A(n.size() + 1, 4);
  Eigen::VectorXd rhs(n.size() + 1);
  for (size_t i = 0; i < n.size(); ++i) {
    const Eigen::Vector3d m = Eigen::AngleAxisd(k * count[i], axis) * cal.normal0_H;
    A.row(i) << m.transpose(), 1.0;
    rhs[i] = -d[i];
  }
  A.row(n.size()) << axis.transpose(), 0.0;
  rhs[n.size()] = 0.0;
  const Eigen::Vector4d x = A.colPivHouseholderQr().solve(rhs);
  cal.point_H = x.head<3>();
  cal.offset_m = x[3];
  cal.counts_used = static_cast<int>(n.size());
  return cal;
}

namespace {

// The model's parameters as one vector: axis (3, normalised in use), normal at count 0 (3,
// normalised), rad_per_count, point on the axis (3), offset.
using Params = Eigen::Matrix<double, 11, 1>;

Params ToParams(const robot::LaserCalibration& c) {
  Params x;
  x << c.axis_H, c.normal0_H, c.rad_per_count, c.point_H, c.offset_m;
  return x;
}

robot::LaserCalibration FromParams(const Params& x, robot::LaserCalibration c) {
  c.axis_H = x.segment<3>(0).normalized();
  c.normal0_H = x.segment<3>(3).normalized();
  c.rad_per_count = x[6];
  c.point_H = x.segment<3>(7) - x.segment<3>(7).dot(c.axis_H) * c.axis_H;  // any axis point
  c.offset_m = x[10];
  return c;
}

Eigen::VectorXd Residuals(const Params& x, const std::vector<CountedPoint>& pts) {
  const robot::LaserCalibration c = FromParams(x, {});
  Eigen::VectorXd r(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) r[i] = c.PlaneH(pts[i].count).SignedDistance(pts[i].p_H);
  return r;
}

}  // namespace

robot::LaserCalibration RefineOnPoints(const robot::LaserCalibration& initial,
                                       const std::vector<CountedPoint>& points_H, double* rms_m) {
  // Levenberg-Marquardt with a numerical Jacobian: 11 parameters, the distances of the stripe
  // points from the model's plane at their counts (metres, where the scene is).
  Params x = ToParams(initial);
  Eigen::VectorXd r = Residuals(x, points_H);
  double cost = r.squaredNorm(), lambda = 1e-3;
  for (int iter = 0; iter < 50; ++iter) {
    Eigen::MatrixXd J(points_H.size(), 11);
    for (int j = 0; j < 11; ++j) {
      Params xp = x;
      const double h = j == 6 ? 1e-9 : 1e-7;
      xp[j] += h;
      J.col(j) = (Residuals(xp, points_H) - r) / h;
    }
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Eigen::MatrixXd A = JtJ;
      A.diagonal() += lambda * JtJ.diagonal().cwiseMax(1e-12);
      const Params step = -A.ldlt().solve(g);
      const Params xn = x + step;
      const Eigen::VectorXd rn = Residuals(xn, points_H);
      if (rn.squaredNorm() < cost) {
        const bool converged = cost - rn.squaredNorm() < 1e-12 * cost;
        x = xn, r = rn, cost = rn.squaredNorm(), lambda *= 0.3, improved = true;
        if (converged) iter = 50;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  if (rms_m != nullptr) *rms_m = std::sqrt(cost / std::max<size_t>(1, points_H.size()));
  robot::LaserCalibration out = FromParams(x, initial);
  return out;
}

}  // namespace hgrasp::scan
