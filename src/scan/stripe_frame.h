#pragma once
/// @file One stereo frame of a laser sweep: rectify, find stripe candidates on every row of both
/// images, keep the pair that best satisfies the light plane (paper eq. 4-5), reconstruct.

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <vector>

#include "scan/stereo_geometry.h"
#include "scan/stripe_detector.h"

namespace hgrasp::scan {

struct StripeFrameConfig {
  StripeDetectorConfig detector;
  /// A pair is valid when |xL + alpha xR + beta y + gamma f| is below this (pixels): five times
  /// the residue's spread on the calibrated simulated robot (0.06 px RMS, camera noise 2).
  double max_residue_px = 0.3;
  /// Points outside this range from the cameras (m) are not the workspace: rejected.
  double min_range_m = 0.2, max_range_m = 2.0;
  /// false: single-camera light-plane triangulation from the left image, no validation (only to
  /// measure what stereo validation buys).
  bool stereo = true;
};

/// A stripe point found on one rectified row.
struct StripePoint {
  int row = 0;            ///< rectified image row
  double xL = 0, xR = 0;  ///< stripe columns relative to the principal point (xR unset in
                          ///< single-camera mode)
  double residue = 0;     ///< eq. 5 residue of the measured pair (pixels)
  Eigen::Vector3d p_M;    ///< the point in frame M (m)
};

struct StripeFrameResult {
  std::vector<StripePoint> points;
  /// Rows with candidates whose point was refused: no pair within max_residue_px (stereo), or
  /// a point outside [min_range_m, max_range_m].
  int rejected = 0;
};

/// The best pair of a row: candidate indices and residue, or nullopt when none is within
/// `max_residue` (exposed for tests).
struct RowMatch {
  int left = -1, right = -1;
  double residue = 0;
};
std::optional<RowMatch> MatchRow(const std::vector<StripeCandidate>& left,
                                 const std::vector<StripeCandidate>& right, double cx, double y,
                                 double f, const LaserCoefficients& c, double max_residue);

/// The point on the light plane nearest (in image-plane distance) to the measured pair: the
/// pair is moved onto the line xL + alpha xR + beta y + gamma f = 0, then triangulated.
Eigen::Vector3d ReconstructOnPlane(double xL, double xR, double y, const LaserCoefficients& c,
                                   const Rectification& rect);

/// Single-camera triangulation: the left ray through (xL, y) meets the light plane (in M).
Eigen::Vector3d IntersectLeftRay(double xL, double y, const Plane& plane_M,
                                 const Rectification& rect);

/// Processes frames with one rectification; holds scratch images (not thread-safe).
class StripeFrameProcessor {
 public:
  StripeFrameProcessor(const Rectification* rect, StripeFrameConfig config);

  /// `left`, `right`: unrectified BGR images; `c`: the light plane's coefficients at this
  /// frame's encoder count.
  void Process(const cv::Mat& left, const cv::Mat& right, const LaserCoefficients& c,
               StripeFrameResult* out);

  /// The rectified red channel of the last processed frame (for pictures and tests): after
  /// Process, only the stripe bands are filled (0 elsewhere); after Rectify, all of it.
  const cv::Mat& rectified_red(int camera) const { return rectified_[camera]; }

  /// Every row's candidate pairs (up to `per_image` strongest in each image), as (xL, xR, y),
  /// one vector per row: what the robust self-calibration chooses from. Uses the images of the
  /// last Rectify call (whole images: no light plane is known yet).
  void CandidatePairs(int per_image, std::vector<std::vector<Eigen::Vector3d>>* rows);
  /// Rectifies the red channels only (whole images).
  void Rectify(const cv::Mat& left, const cv::Mat& right);

  /// Columns [first, last] of camera `camera`'s rectified image where the light plane with
  /// coefficients `c` can show a point between min_range_m and max_range_m (plus the
  /// detector's reach): only there can a valid stripe lie.
  std::pair<int, int> StripeBand(int camera, const LaserCoefficients& c) const;

  const StripeFrameConfig& config() const { return config_; }

 private:
  void RectifyBand(int camera, const cv::Mat& image, std::pair<int, int> band);

  const Rectification* rect_;
  StripeFrameConfig config_;
  std::pair<int, int> band_[2];
  cv::Mat red_[2], rectified_[2];
  std::vector<StripeCandidate> candidates_[2];
};

}  // namespace hgrasp::scan
