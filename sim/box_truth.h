#pragma once
/// @file How far a fitted box lies from a true one: ground truth for reports and accuracy tests
/// (never read by the pipeline).

#include <Eigen/Core>
#include <vector>

#include "common/geometry.h"

namespace hgrasp::sim {

/// Errors of a fitted box against the true box, both standing upright (z axes up).
struct BoxError {
  double center_m = 0;  ///< distance between the centres
  /// |fitted - true| per fitted edge (along the fitted box's x, y, z), the fitted horizontal axes
  /// matched to the true ones they are nearest to.
  Eigen::Vector3d edge_m = Eigen::Vector3d::Zero();
  double max_edge_m = 0;  ///< largest of edge_m
  /// Angle between the fitted box's x axis and the nearest of the true box's +-x, +-y axes, about
  /// z (a box's yaw is defined modulo 90 deg): 0..45 deg, in rad.
  double yaw_rad = 0;
  double tilt_rad = 0;  ///< angle between the two boxes' z axes
};

/// Compares a fitted box (X_WO_fit, full edges size_fit) with the true box (X_WO_true, size_true).
BoxError CompareBox(const Pose3& X_WO_true, const Eigen::Vector3d& size_true, const Pose3& X_WO_fit,
                    const Eigen::Vector3d& size_fit);

/// A box: its centre pose in W and full edge lengths (m).
struct PlacedBox {
  Pose3 X_WO;
  Eigen::Vector3d size_O;
};

/// Which fitted box models each true box: per true box, the index of the fitted box whose centre
/// lies nearest to the true centre, kept when that centre lies inside the true box grown by
/// margin_m on every side and no other true box's centre is nearer to it; -1 (missed) otherwise.
/// A fitted box models at most one true box.
std::vector<int> MatchBoxes(const std::vector<PlacedBox>& truth, const std::vector<PlacedBox>& fitted,
                            double margin_m = 0.01);

}  // namespace hgrasp::sim
