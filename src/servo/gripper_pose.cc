#include "servo/gripper_pose.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"

namespace hgrasp::servo {
namespace {

constexpr double kCollinearRatio = 1e-6;  // sigma_2 / sigma_1 of the centred spread
constexpr double kMinSpread_m = 1e-9;     // absolute floor on sigma_2 (RMS distance, m)

Eigen::Vector3d Centroid(const std::vector<Eigen::Vector3d>& p) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& q : p) c += q;
  return c / static_cast<double>(p.size());
}

// True when the points spread in at least two directions (not all on one line).
bool SpansAPlane(const std::vector<Eigen::Vector3d>& p, const Eigen::Vector3d& c) {
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const auto& q : p) spread += (q - c) * (q - c).transpose();
  spread /= static_cast<double>(p.size());
  // Eigenvalues of the spread are squared RMS extents along the principal axes (ascending).
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvalues();
  const double s1 = std::sqrt(std::max(ev(2), 0.0));
  const double s2 = std::sqrt(std::max(ev(1), 0.0));
  return s2 > kMinSpread_m && s2 > kCollinearRatio * s1;
}

void CheckFinite(const std::vector<Eigen::Vector3d>& p, const char* name) {
  for (size_t i = 0; i < p.size(); ++i) {
    if (!p[i].allFinite()) {
      throw InputError("", std::string(name) + "[" + std::to_string(i) + "]", "non-finite",
                       "finite coordinates (m)");
    }
  }
}

}  // namespace

std::optional<Pose3> FitGripperPose(const std::vector<Eigen::Vector3d>& p_E,
                                    const std::vector<Eigen::Vector3d>& p_C, double* rms_m) {
  if (p_E.size() != p_C.size()) {
    throw InputError("", "p_C", std::to_string(p_C.size()) + " points",
                     std::to_string(p_E.size()) + " points, one per LED in p_E");
  }
  CheckFinite(p_E, "p_E");
  CheckFinite(p_C, "p_C");
  if (p_E.size() < 3) return std::nullopt;

  const Eigen::Vector3d c_E = Centroid(p_E);
  const Eigen::Vector3d c_C = Centroid(p_C);
  if (!SpansAPlane(p_E, c_E) || !SpansAPlane(p_C, c_C)) return std::nullopt;

  // Cross-covariance H = sum (p_E - c_E)(p_C - c_C)^T; R_CE = V diag(1, 1, d) U^T with
  // H = U S V^T and d = sign(det(V U^T)), which keeps the rotation proper (Umeyama 1991).
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < p_E.size(); ++i) H += (p_E[i] - c_E) * (p_C[i] - c_C).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  Eigen::Vector3d d(1.0, 1.0, (V * U.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
  const Eigen::Matrix3d R_CE = V * d.asDiagonal() * U.transpose();

  Pose3 X_CE = Pose3::Identity();
  X_CE.linear() = R_CE;
  X_CE.translation() = c_C - R_CE * c_E;

  if (rms_m != nullptr) {
    double sum_sq = 0.0;
    for (size_t i = 0; i < p_E.size(); ++i) sum_sq += (X_CE * p_E[i] - p_C[i]).squaredNorm();
    *rms_m = std::sqrt(sum_sq / static_cast<double>(p_E.size()));
  }
  return X_CE;
}

}  // namespace hgrasp::servo
