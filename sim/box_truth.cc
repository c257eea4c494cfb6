#include "sim/box_truth.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::sim {

BoxError CompareBox(const Pose3& X_WO_true, const Eigen::Vector3d& size_true, const Pose3& X_WO_fit,
                    const Eigen::Vector3d& size_fit) {
  BoxError e;
  e.center_m = (X_WO_fit.translation() - X_WO_true.translation()).norm();
  const Eigen::Matrix3d& Rt = X_WO_true.linear();
  const Eigen::Matrix3d& Rf = X_WO_fit.linear();
  e.tilt_rad = std::acos(std::clamp(Rt.col(2).dot(Rf.col(2)), -1.0, 1.0));
  // The fitted x axis is matched to the true horizontal axis it is most parallel to.
  const double cx = std::abs(Rf.col(0).dot(Rt.col(0)));
  const double cy = std::abs(Rf.col(0).dot(Rt.col(1)));
  const bool swapped = cy > cx;
  e.yaw_rad = std::acos(std::clamp(std::max(cx, cy), 0.0, 1.0));
  const Eigen::Vector3d matched(swapped ? size_true.y() : size_true.x(),
                                swapped ? size_true.x() : size_true.y(), size_true.z());
  e.edge_m = (size_fit - matched).cwiseAbs();
  e.max_edge_m = e.edge_m.maxCoeff();
  return e;
}

std::vector<int> MatchBoxes(const std::vector<PlacedBox>& truth, const std::vector<PlacedBox>& fitted,
                            double margin_m) {
  const auto nearest_truth = [&](const Eigen::Vector3d& p_W) {
    int best = -1;
    double best_d = 1e300;
    for (size_t i = 0; i < truth.size(); ++i) {
      const double d = (truth[i].X_WO.translation() - p_W).norm();
      if (d < best_d) best_d = d, best = static_cast<int>(i);
    }
    return best;
  };
  std::vector<int> match(truth.size(), -1);
  for (size_t i = 0; i < truth.size(); ++i) {
    int best = -1;
    double best_d = 1e300;
    for (size_t k = 0; k < fitted.size(); ++k) {
      const double d = (fitted[k].X_WO.translation() - truth[i].X_WO.translation()).norm();
      if (d < best_d) best_d = d, best = static_cast<int>(k);
    }
    if (best < 0) continue;
    const Eigen::Vector3d p_O = truth[i].X_WO.inverse() * fitted[best].X_WO.translation();
    const bool inside = (p_O.cwiseAbs().array() <= 0.5 * truth[i].size_O.array() + margin_m).all();
    if (inside && nearest_truth(fitted[best].X_WO.translation()) == static_cast<int>(i)) {
      match[i] = best;
    }
  }
  return match;
}

}  // namespace hgrasp::sim
