#pragma once
/// @file Laser light on the rendered scene: where a sheet of laser light meets a surface that it
/// lights and a camera sees, that camera's image gets a red stripe.
///
/// The scene is static while the laser sweeps, so each camera's colour, depth and labels are
/// rendered once per head pose (sim/renderer.h) and each frame's stripes are composited from them:
/// for every image row, the sub-pixel column where the surface crosses the light sheet is found
/// exactly for planar surfaces (1/z is linear in the image along a row of a plane), the crossing
/// is dropped at depth discontinuities and where the laser's path to it is blocked, and a
/// Gaussian profile (sheet thickness seen on the surface, blurred by the lens, integrated over
/// the pixel) is added with a brightness that follows the surface's reflectance of red light.

#include <Eigen/Core>
#include <functional>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "common/geometry.h"
#include "common/pinhole_camera.h"
#include "sim/renderer.h"

namespace hgrasp::sim {

/// Optical constants of the stripe (our choices; see models/humanoid.xml for the laser).
struct StripeOptics {
  double sheet_sigma_m = 0.0008;  ///< Gaussian half-thickness of the light sheet (m)
  double psf_sigma_px = 0.6;      ///< lens blur (pixels)
  /// Grey levels for a white surface 0.6 m away facing the laser. Bright enough that the stripe
  /// shows on dark faces lit at a slant (a blue box's front: red reflectance 0.15, incidence about
  /// 60 deg, about 10 grey levels); white surfaces near the laser then clip.
  double gain = 600.0;
  double reference_range_m = 0.6;
  /// Camera response to the red laser light per channel (B, G, R): mostly red, some crosstalk.
  Eigen::Vector3d channel_response{0.06, 0.12, 1.0};
  /// Depth continuity: a crossing between two pixels is a surface only when their depth step is
  /// at most this factor times the steps on either side (plus the small absolute slack below).
  double jump_factor = 3.0;
  double jump_slack_m = 0.002;
};

/// A sheet of laser light: our own stripe, another robot's, or a mirror image of one.
struct LightSheet {
  Plane plane_W;             ///< the sheet's centre plane
  Eigen::Vector3d source_W;  ///< where the light comes from (the generator, or its mirror)
  double gain_scale = 1.0;   ///< relative power (1 for our laser)
  /// Whether the sheet's light reaches surface point p_W (shadow test, mirror aperture); it
  /// must return false for points the light cannot reach.
  std::function<bool(const Eigen::Vector3d& p_W)> reaches;
};

/// One camera's view as the stripe needs it, computed once per head pose.
struct CameraView {
  PinholeCamera camera;
  Pose3 X_WC;
  CameraImages images;  ///< ambient colour, depth (m), labels (geom ids)
  cv::Mat points_W;     ///< (H x W) CV_64FC3: surface point of each pixel in W (m)
  cv::Mat normals_W;    ///< (H x W) CV_64FC3: unit surface normal (towards the camera)
  /// Red reflectance (0-1) per geom id: the surface colour that the laser light follows.
  std::vector<double> red_reflectance;

  /// Builds points and normals from the images.
  static CameraView Make(const PinholeCamera& camera, const Pose3& X_WC, CameraImages images,
                         std::vector<double> red_reflectance);
};

/// The exact centre of each stripe crossing found on a row (for tests and ground truth).
struct StripeCrossing {
  int sheet = 0;  ///< index of the light sheet in the list given to AddStripes
  int row = 0;
  double column = 0.0;    ///< sub-pixel column of the stripe centre
  Eigen::Vector3d p_W;    ///< the lit surface point
  double peak = 0.0;      ///< brightness of the centre before saturation (grey levels)
  double sigma_px = 0.0;  ///< profile width (pixels)
};

/// Adds the light of `sheets` to `radiance` ((H x W) CV_32FC3, B G R grey levels, unclamped)
/// and returns every crossing drawn.
std::vector<StripeCrossing> AddStripes(const CameraView& view,
                                       const std::vector<LightSheet>& sheets,
                                       const StripeOptics& optics, cv::Mat* radiance);

}  // namespace hgrasp::sim
