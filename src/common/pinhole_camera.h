#pragma once
/// @file The pinhole camera model shared by the simulator and the pipeline.
///
/// Pixel coordinates (u, v) are continuous with the centre of pixel (column i, row j) at
/// (i, j): the image spans u in [-0.5, width - 0.5]. The optical frame C has x right, y down,
/// z forward (DESIGN.md rule 4).

#include <Eigen/Core>
#include <optional>

namespace hgrasp {

struct PinholeCamera {
  int width = 320;   ///< pixels
  int height = 240;  ///< pixels
  double fx = 0.0;   ///< focal length in pixels along u
  double fy = 0.0;   ///< focal length in pixels along v
  double cx = 0.0;   ///< principal point u, pixels
  double cy = 0.0;   ///< principal point v, pixels

  /// An ideal camera of the given vertical field of view (rad) with the principal point at the
  /// image centre and square pixels: what MuJoCo renders for a camera with that fovy.
  static PinholeCamera FromFovy(int width, int height, double fovy_rad);

  /// Pixel of point p_CQ (camera frame, m); nullopt when it lies behind the camera (z <= 0).
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_CQ) const;

  /// Unit-z ray direction (x/z, y/z, 1) in C through pixel (u, v).
  Eigen::Vector3d Ray(double u, double v) const;

  /// True when (u, v) lies inside the image area.
  bool Contains(const Eigen::Vector2d& uv) const;

  /// The 3x3 intrinsic matrix K.
  Eigen::Matrix3d K() const;
};

}  // namespace hgrasp
