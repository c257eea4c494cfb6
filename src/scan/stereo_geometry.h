#pragma once
/// @file Rectified stereo geometry and the light-plane validation coefficients of Taylor &
/// Kleeman (ACRA 2002, section 4; IJRR 2004).
///
/// After rectification both cameras share one orientation and one intrinsic matrix; epipolar
/// lines are image rows. Frame M is the paper's: origin midway between the camera centres, axes
/// those of the rectified cameras (x right, y down, z forward); the left camera sits at x = -b,
/// the right at x = +b. Image coordinates x, y are rectified pixels relative to the principal
/// point. A point (X, Y, Z) in M images at xL = (X + b) f / Z, xR = (X - b) f / Z, y = Y f / Z.
/// A light plane A X + B Y + C Z + D = 0 in M makes every valid stripe pair satisfy
///   xL + alpha xR + beta y + gamma f = 0                                         (paper eq. 5)
/// with alpha = (A b - D) / (A b + D), beta = 2 B b / (A b + D), gamma = 2 C b / (A b + D).

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "common/geometry.h"
#include "common/pinhole_camera.h"

namespace hgrasp::scan {

/// The paper's coefficients of one light plane (eq. 4-5).
struct LaserCoefficients {
  double alpha = -1.0, beta = 0.0, gamma = 0.0;

  /// Residue xL + alpha xR + beta y + gamma f of a stripe pair (pixels).
  double Residue(double xL, double xR, double y, double f) const {
    return xL + alpha * xR + beta * y + gamma * f;
  }
};

/// Coefficients of plane_M for half-baseline b (m). The plane must not pass through the right
/// camera's centre (+b, 0, 0), A b + D = 0: the stripe would be edge-on in that camera.
LaserCoefficients CoefficientsFromPlane(const Plane& plane_M, double b);
/// The plane (unit normal) the coefficients describe, for half-baseline b.
Plane PlaneFromCoefficients(const LaserCoefficients& c, double b);

/// Rectification of one stereo pair at one verge angle.
struct Rectification {
  double f = 0.0;             ///< rectified focal length (pixels), both cameras
  double cx = 0.0, cy = 0.0;  ///< rectified principal point (pixels), both cameras
  double b = 0.0;             ///< half the baseline (m)
  int width = 0, height = 0;
  Eigen::Matrix3d R_RC[2];   ///< rotation from camera c's optical frame to rectified
  cv::Mat map1[2], map2[2];  ///< cv::remap maps per camera (fixed point, CV_16SC2)
  Pose3 X_CLM;               ///< frame M in the left camera's optical frame

  /// Point in M from a pair on rectified row coordinate y (all relative to the principal
  /// point, pixels): plain stereo triangulation.
  Eigen::Vector3d Triangulate(double xL, double xR, double y) const;
  /// Pixel (u, v) in the unrectified image of camera `camera` of a point in M.
  Eigen::Vector2d ProjectToCamera(int camera, const PinholeCamera& k,
                                  const Eigen::Vector3d& p_M) const;
};

/// Rectifies the pair with intrinsics `left`, `right` (no lens distortion) and the right
/// camera's pose in the left camera's optical frame, with OpenCV's stereoRectify
/// (CALIB_ZERO_DISPARITY: one principal point for both).
Rectification MakeRectification(const PinholeCamera& left, const PinholeCamera& right,
                                const Pose3& X_CLCR);

}  // namespace hgrasp::scan
