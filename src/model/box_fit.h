#pragma once
/// @file Fitting a generic box model to one object's planar regions (Taylor & Kleeman, section
/// 5.2): the top face and one or two visible sides give the normals and the near faces'
/// distances; the hidden faces are placed at the robust extreme of the visible faces' edge points.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

#include "common/geometry.h"
#include "scan/range_image.h"
#include "segment/segment.h"

namespace hgrasp::model {

/// A fitted box.
struct BoxModel {
  /// Pose of the box frame O in W, at the box's centre (m): O's z axis is the top face's normal
  /// (up), x and y lie along the box's horizontal edges (right-handed).
  Pose3 X_WO = Pose3::Identity();
  /// Full edge lengths along O's x, y and z (m).
  Eigen::Vector3d size_O = Eigen::Vector3d::Zero();
  /// Corners in W (m); corner k is at X_WO * (+-size_O / 2) with bit 0 of k choosing the sign
  /// along x, bit 1 along y and bit 2 along z (set: +).
  std::array<Eigen::Vector3d, 8> vertices_W{};
  std::vector<int> regions;  ///< ids of the regions it was fitted to (the visible faces)
  int points = 0;            ///< range cells on those regions
};

/// Thresholds of the box fit.
struct BoxFitConfig {
  /// Angular tolerance (deg): a top face is within this of horizontal, side faces within this of
  /// vertical, and the second side within this of perpendicular to the first.
  double max_face_angle_deg = 10;
  /// The top face and the largest side need at least this many range cells; a smaller second
  /// side is ignored (treated as hidden).
  double min_face_cells = 30;
};

/// Fits a box to one object group (paper 5.2). The largest region of the group within
/// max_face_angle_deg of horizontal is the top A1 (normal n1); the largest near-vertical region
/// is the side A2, and the largest other near-vertical region nearly perpendicular to A2 (if any)
/// is A3. n2 is A2's normal made perpendicular to n1, n3 = n1 x n2. The visible faces' distances
/// along their normals come from their centroids. Each hidden face B_i lies at the edge points'
/// robust extreme along n_i (their 99th percentile; edge points: cells of the other visible faces
/// with a 4-neighbour that is invalid, outside the image or labelled differently), at least 1 cm
/// beyond A_i on the side away from the cameras. The paper places it by a vote for the densest
/// line of edge points; the scanner's ragged face ends (the stripe crosses them at a slant) make
/// that line fall 5-8 mm inside the true edge, so the extreme is used. With A3 hidden, both ends
/// along n3 are such extremes. The bottom is the table,
/// z = 0. Returns nullopt (never a wrong box) when there is no top face or no side face, the top
/// or A2 has fewer than min_face_cells cells, no edge point lies beyond a visible face, or an edge
/// of the result is shorter than 1 cm or longer than 0.5 m. s must come from segment::SegmentPlanes
/// on range (aborts on a size mismatch); unknown region ids are ignored.
std::optional<BoxModel> FitBox(const segment::SegmentResult& s,
                               const std::vector<int>& object_regions,
                               const scan::RangeImage& range, const BoxFitConfig& config = {});

/// FitBox on every object of a grouping, in order; objects whose fit fails are skipped and
/// counted in *failed (when not null).
std::vector<BoxModel> FitBoxes(const segment::SegmentResult& s, const segment::Grouping& g,
                               const scan::RangeImage& range, int* failed = nullptr,
                               const BoxFitConfig& config = {});

}  // namespace hgrasp::model
