#pragma once
/// @file Laser stripe candidates on one rectified image row.
///
/// The stripe is a narrow bright ridge in the red channel. A pixel is a candidate when it is a
/// local maximum standing above both neighbours `half_width` pixels away by at least
/// `min_contrast` grey levels: ambient light and slow shading cancel, and a colour edge (bright
/// on one side only) fails, as does a stripe whose two sides lie on different surfaces. The
/// sub-pixel centre comes from a Gaussian through the three pixels around the maximum (background
/// removed), or from the centroid of a saturated plateau.

#include <cstdint>
#include <vector>

namespace hgrasp::scan {

struct StripeDetectorConfig {
  int half_width = 3;    ///< pixels to each side where the background is read
  int min_contrast = 8;  ///< grey levels above both sides
  /// The two sides' background may differ by at most this fraction of the peak's height: a
  /// stripe cut off by an occluding edge (one side another surface) is not located reliably.
  /// When the samples half_width out fail this, the nearest ones clear of the stripe's core
  /// (2 pixels out) may stand in on one side: an edge 2-3 pixels from the stripe leaves its
  /// core on one surface.
  double max_background_step = 0.5;
  int max_candidates = 8;  ///< strongest kept per row
  int saturation = 255;    ///< grey level at which the camera clips
};

struct StripeCandidate {
  double x = 0.0;         ///< sub-pixel column (pixel centres at integers)
  double contrast = 0.0;  ///< peak height above the background (grey levels)
};

/// Candidates on `row` (length `width`, one channel), strongest first, at most
/// `config.max_candidates`. `out` is cleared first. With `ambient` (the same row with the laser
/// off, `width` long), the stripe is searched in row - ambient, so that it stands on a flat
/// background even where a dark surface meets a bright one; pixels of `row` at the saturation
/// level are known as clipped either way.
void DetectStripeCandidates(const std::uint8_t* row, int width, const StripeDetectorConfig& config,
                            std::vector<StripeCandidate>* out,
                            const std::uint8_t* ambient = nullptr);

}  // namespace hgrasp::scan
