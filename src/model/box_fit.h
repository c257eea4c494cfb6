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
  /// With no side face seen (the sides edge-on to the cameras), a top of at least this many
  /// cells whose convex hull fills at least min_top_fill of its minimum-area rectangle gives the
  /// box alone: the bottom is the table.
  int min_top_only_cells = 200;
  double min_top_fill = 0.85;
};

/// A box model from its pose and full edges (vertices_W filled; no regions, no points): e.g.
/// a true box, to plan on what the scene holds.
BoxModel MakeBox(const Pose3& X_WO, const Eigen::Vector3d& size_O);

/// Fits a box to one object group (paper 5.2). The largest region of the group within
/// max_face_angle_deg of horizontal is the top A1 (normal n1); the largest near-vertical region
/// is the side A2, and the largest other near-vertical region nearly perpendicular to A2 (if any)
/// is A3. n2 is A2's normal made perpendicular to n1, n3 = n1 x n2. The visible faces' distances
/// along their normals come from their centroids. Each hidden side face B_i lies at the edge
/// points' robust extreme along n_i (their 99th percentile, plus a quarter of the top's cell
/// spacing along n_i: the outermost cells lie inside the true edge), at least 1 cm beyond A_i on
/// the side away from the cameras; with A3 hidden, both ends along n3 are such extremes. Edge
/// points are the cells of the top (within max(2 mm, 3 sigma) of its plane) and of the sides' upper
/// halves with a 4-neighbour that is invalid, outside the image or labelled differently: near the
/// table a side's region can take in table cells along the line where its plane meets the table.
/// The paper places a hidden face by a vote for the densest line of edge points; the scanner's
/// ragged face ends (the stripe crosses them at a slant) make that line fall 5-8 mm inside the true
/// edge, so the extreme is used. The bottom is the table, z = 0. With no side face of
/// min_face_cells (the sides seen edge-on), the top alone gives the box when it has
/// min_top_only_cells and a rectangular outline (see BoxFitConfig): n2 along the outline, both ends
/// along n2 and n3 from the edge points' extremes. Returns nullopt (never a wrong box) when there
/// is no top face of min_face_cells, no side face and a top too small or not rectangular (a sliver,
/// a partly hidden top), no edge point lies beyond a visible face, or an edge of the result is
/// shorter than 1 cm or longer than 0.5 m. s must come from segment::SegmentPlanes on range (aborts
/// on a size mismatch); unknown region ids are ignored.
std::optional<BoxModel> FitBox(const segment::SegmentResult& s,
                               const std::vector<int>& object_regions,
                               const scan::RangeImage& range, const BoxFitConfig& config = {});

/// FitBox on every object of a grouping, in order; objects whose fit fails are skipped and
/// counted in *failed (when not null).
std::vector<BoxModel> FitBoxes(const segment::SegmentResult& s, const segment::Grouping& g,
                               const scan::RangeImage& range, int* failed = nullptr,
                               const BoxFitConfig& config = {});

}  // namespace hgrasp::model
