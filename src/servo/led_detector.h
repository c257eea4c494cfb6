#pragma once
/// @file The gripper LEDs in the stereo images (paper section 6): bright red blobs with
/// sub-pixel centroids in each raw image, matched between the cameras on rectified rows and
/// triangulated to positions in the left camera's optical frame.

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "robot/calibration.h"
#include "scan/stereo_geometry.h"

namespace hgrasp::servo {

/// One bright red blob in one raw (unrectified) camera image.
struct LedBlob {
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  ///< sub-pixel centroid (u, v), raw image
  double area_px = 0.0;                          ///< pixels in the blob
  double peak = 0.0;                             ///< largest redness R - max(G, B) in the blob
};

/// Thresholds of the LED detector (grey levels 0-255, 8-bit BGR images).
struct LedDetectorConfig {
  /// A pixel belongs to a blob when its redness R - max(G, B) reaches this ...
  double min_redness = 90.0;
  /// ... and its red channel reaches this. A lit LED is emissive and saturates red (the
  /// simulated ones render about (R, G, B) = (254, 65, 44)); a lit red surface stays well below
  /// (a saturated red box under the default lighting renders about (180, 12, 10)).
  double min_red = 230.0;
  /// A blob's largest redness must reach this (rejects blobs of marginal pixels only).
  double min_peak = 150.0;
  int min_area_px = 1;    ///< smaller blobs are noise
  int max_area_px = 400;  ///< larger blobs are red objects, not LEDs
  /// Longer side over shorter side of a blob's bounding box, at most: a laser stripe (red, thin
  /// and long) is no LED.
  double max_elongation = 3.0;
  /// The centroid sums redness above this floor (the background's redness is about 0 give or
  /// take the camera noise), capped by the pixel's red above the background's (the median red
  /// of the grown box's rim: a red surface behind the LED would pull the centroid) ...
  double weight_floor = 10.0;
  /// ... over the blob's bounding box grown by this many pixels.
  int centroid_margin_px = 3;
};

/// The LED blobs of a BGR (CV_8UC3) image: 8-connected components of the redness mask, each
/// located at its redness-weighted centroid (weights redness - weight_floor over the blob's
/// grown bounding box). Sorted by v, then u.
std::vector<LedBlob> DetectLeds(const cv::Mat& bgr, const LedDetectorConfig& config = {});

/// An LED seen by both cameras.
struct LedPoint {
  Eigen::Vector3d p_CL = Eigen::Vector3d::Zero();      ///< position in the left optical frame (m)
  Eigen::Vector2d left_px = Eigen::Vector2d::Zero();   ///< centroid in the raw left image
  Eigen::Vector2d right_px = Eigen::Vector2d::Zero();  ///< centroid in the raw right image
  double row_error_px = 0.0;  ///< rectified row of the right blob minus that of the left
};

/// Pixel `px` of raw image `camera` (0 left, 1 right, intrinsics `k`) in rectified image
/// coordinates (pixels, absolute: the principal point is (rect.cx, rect.cy)).
Eigen::Vector2d RectifyPoint(const scan::Rectification& rect, int camera, const PinholeCamera& k,
                             const Eigen::Vector2d& px);

struct LedMatchConfig {
  double max_row_diff_px = 1.5;   ///< largest rectified row difference of a matched pair
  double min_disparity_px = 0.5;  ///< smallest rectified disparity xL - xR (point in front)
};

/// Matches left and right blobs by rectified row and triangulates each pair. Pairs are taken
/// greedily, closest rows first; each blob is used at most once; a pair needs a row difference
/// within max_row_diff_px and a disparity of at least min_disparity_px. Triangulation uses the
/// mean of the two rows. `rect` must be the rectification of `cameras` at the verge angle of
/// the exposure. Sorted by left v, then u.
std::vector<LedPoint> MatchAndTriangulate(const std::vector<LedBlob>& left,
                                          const std::vector<LedBlob>& right,
                                          const robot::StereoIntrinsics& cameras,
                                          const scan::Rectification& rect,
                                          const LedMatchConfig& config = {});

}  // namespace hgrasp::servo
