#pragma once
/// @file A scan scored against the simulator's truth, frame by frame (for reports, sweeps and
/// tests; never read by the pipeline): how far the range points lie from the true surfaces, how
/// many are outliers, and how much of the stripe that both cameras truly saw was measured.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string_view>
#include <vector>

#include "sim/stereo_rig.h"
#include "sim/world.h"

namespace hgrasp::sim {

/// A range point beyond this distance (m) from every true surface is an outlier.
constexpr double kOutlierDistanceM = 0.005;
/// A truth stripe point is covered when a range point of its frame lies within this (m).
constexpr double kCoverageRadiusM = 0.005;

struct ScanTruthFigures {
  int points = 0;        ///< range points scored
  double rms_m = 0;      ///< RMS distance to the nearest true surface (m), all points
  double median_m = 0;   ///< median of that distance (m)
  double p99_m = 0;      ///< its 99th percentile (m)
  int outliers = 0;      ///< points farther than kOutlierDistanceM
  int truth_points = 0;  ///< true stripe points (one per image row) both cameras saw
  int covered = 0;       ///< of those, measured (kCoverageRadiusM, same frame)
  double outlier_fraction() const { return points > 0 ? double(outliers) / points : 0.0; }
  double coverage() const { return truth_points > 0 ? double(covered) / truth_points : 0.0; }
};

/// Collects, for each frame of a sweep, the points of our own stripe that the left camera drew
/// and the right camera sees unoccluded (the rig's last exposure), keyed by the frame's laser
/// encoder count; then scores the scan's points (each tagged with its frame's count) against
/// them and against the true surfaces of the world (which must not have moved since).
class ScanTruth {
 public:
  /// Records the truth of the exposure `rig` made last, the frame latched at `encoder_count`.
  /// Frames with the same count pool their truth points.
  void AddFrame(StereoRig& rig, std::int32_t encoder_count);

  /// Frames recorded.
  int frames() const { return frames_; }

  /// A range point p_W measured in the frame latched at encoder_count.
  struct Point {
    std::int32_t encoder_count;
    Eigen::Vector3d p_W;
  };
  /// Scores `points` (a scan of the frames latched at `frame_counts`, e.g. the range image's
  /// columns): the truth of recorded frames at other counts (frames the scan did not use) is
  /// left out.
  ScanTruthFigures Score(const World& world, const std::vector<Point>& points,
                         const std::vector<std::int32_t>& frame_counts) const;

 private:
  std::map<std::int32_t, std::vector<Eigen::Vector3d>> truth_;
  int frames_ = 0;
};

/// The name of the random scenes' palette colour (sim::RandomScenePalette) nearest to `rgb` (RGB
/// 0-1, Euclidean): the colour a scenario's object truly has, in the words targets use.
std::string_view NearestPaletteName(const Eigen::Vector3d& rgb);

/// The name of the colour an object truly has: its scenario's color_name when given (a colour
/// drawn around a palette colour, as the wide scenes draw them), else NearestPaletteName of its
/// albedo.
std::string_view TrueColorName(const ObjectSpec& object);

}  // namespace hgrasp::sim
