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
  /// Candidates weaker than detector.min_contrast but at least this strong (grey levels) are
  /// kept when the stripe continues through them: a candidate within k max_support_step_px on
  /// the rows k = 1 and 2 above and below. The light plane cuts a surface in a continuous curve,
  /// camera noise seldom lines up over three rows: dim stripes (dark faces lit at a slant) are
  /// found without admitting noise peaks.
  int weak_contrast = 5;
  double max_support_step_px = 1.5;
  /// Stereo: a point with no other point of the frame within this distance (m) on the two rows
  /// above and below is refused. The light plane cuts a surface in a continuous curve; a lone
  /// point is a chance pairing of two unrelated candidates (noise, another stripe).
  double max_neighbour_gap_m = 0.01;
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
  /// Rows with candidates whose point was refused: no pair within max_residue_px (stereo), a
  /// point outside [min_range_m, max_range_m], or a lone point (stereo; max_neighbour_gap_m).
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

  /// The images with the laser off (unrectified BGR, head where it is for the frames): from now
  /// on, Process searches the stripe in each frame's rectified red channel less theirs (see
  /// DetectStripeCandidates), so that it stands on a flat background even where a dark surface
  /// meets a bright one. Empty images switch this off. Setting the same images again is cheap.
  void SetAmbient(const cv::Mat& left, const cv::Mat& right);

  /// Columns [first, last] of camera `camera`'s rectified image where the light plane with
  /// coefficients `c` can show a point between min_range_m and max_range_m (plus the
  /// detector's reach): only there can a valid stripe lie.
  std::pair<int, int> StripeBand(int camera, const LaserCoefficients& c) const;

  const StripeFrameConfig& config() const { return config_; }

 private:
  void RectifyBand(int camera, const cv::Mat& image, std::pair<int, int> band);
  /// Removes the points with no neighbour (max_neighbour_gap_m, rows +-2); counts them rejected.
  void RejectIsolated(StripeFrameResult* out) const;

  const Rectification* rect_;
  StripeFrameConfig config_;
  std::pair<int, int> band_[2];
  cv::Mat red_[2], rectified_[2];
  cv::Mat ambient_[2], ambient_rectified_[2];  // as given (BGR); rectified red channel
  std::vector<StripeCandidate> candidates_[2];
  std::vector<std::vector<StripeCandidate>> rows_[2];  // per row, before the support test
};

}  // namespace hgrasp::scan
