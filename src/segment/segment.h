#pragma once
/// @file Range data segmentation into planar regions, and floor/wall removal and grouping of the
/// remaining regions into objects (Taylor & Kleeman, section 5.1).

#include <Eigen/Core>
#include <vector>

#include "scan/range_image.h"

namespace hgrasp::segment {

/// Thresholds of the segmentation. Lengths in m, squared lengths (plane-fit residuals, i.e. mean
/// squared distances to the fitted plane) in m^2.
struct SegmentConfig {
  /// Side of the square patch of range cells used per normal estimate (odd, >= 3); N = patch^2.
  int patch = 5;
  /// A patch whose plane-fit residual (smallest eigenvalue of its covariance, m^2) exceeds this
  /// has no valid normal (e.g. at depth discontinuities); 2 mm std -> 4e-6 m^2.
  double max_patch_residual_m2 = 4e-6;
  /// Coplanarity test of neighbouring cells (paper): n1 . n2 > alpha1.
  double alpha1 = 0.9;
  /// Coplanarity test of neighbouring cells (paper): max(|r12 . n1|, |r12 . n2|) < alpha2.
  double alpha2 = 0.1;
  /// Merging stops when the cheapest merge's plane-fit residual (m^2) exceeds this.
  double max_merge_residual_m2 = 4e-6;
  /// Passes of boundary refinement after merging: a cell next to another region whose plane it
  /// lies nearer moves there (0: none).
  int refine_passes = 3;
  /// Regions with fewer cells are dropped at the end.
  int min_region_cells = 30;
  /// Two 4-neighbouring cells are connected only if their 3-D points are closer than this (m);
  /// objects are assumed not to touch.
  double max_neighbour_gap_m = 0.01;
  /// Grouping regions into objects bridges up to this many missing cells of the range image
  /// (the scan leaves gaps along a box's edges, where the stripe is cut) ...
  int group_reach_cells = 3;
  /// ... between points this close (m): objects do not touch (paper 5.1).
  double max_group_gap_m = 0.015;
};

/// One planar region of a SegmentResult.
struct PlaneRegion {
  int id = -1;  ///< its label in SegmentResult::labels
  /// Unit plane normal in W: n.z >= 0 for near-horizontal planes (|n.z| >= cos 45 deg), else
  /// n.x <= 0 (facing the robot; ties at n.x == 0 broken by n.y <= 0).
  Eigen::Vector3d normal_W = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d centroid_W = Eigen::Vector3d::Zero();  ///< mean of the region's points (m)
  double residual_m2 = 0.0;  ///< smallest eigenvalue of the region's covariance (m^2)
  int cells = 0;             ///< number of range cells labelled with id
};

/// Labels per range cell and the planar regions they refer to.
struct SegmentResult {
  std::vector<int> labels;  ///< rows x cols, row-major; -1 unlabelled or invalid
  int rows = 0, cols = 0;
  std::vector<PlaneRegion> regions;  ///< regions[k].id are distinct; ids need not be contiguous
};

/// Segments a range image into planar regions (paper 5.1):
///  1. patch normals: a plane fitted to the valid cells of each patch x patch window (moment sums
///     from a separable box filter); residual above max_patch_residual_m2 -> no normal;
///  2. initial segmentation by sequential binary connectivity with the paper's coplanarity tests
///     (n1.n2 > alpha1, max(|r12.n1|, |r12.n2|) < alpha2, r12 between the two patches' means, the
///     paper's m_i) between 4-neighbours closer than max_neighbour_gap_m;
///  3. cells without a valid normal join the neighbouring region whose plane they satisfy
///     (distance < 3 sqrt(max_patch_residual_m2)), nearest plane first;
///  4. region merging by boundary-cost minimisation: repeatedly merge the adjacent pair whose
///     merged plane fit has the smallest residual, until that exceeds max_merge_residual_m2.
///     Per-region moment sums make a merged residual O(1); adjacent regions of at most three cells
///     together (cost exactly 0) merge first; then each region keeps its neighbours' merge costs
///     (recomputed when either changes) and an indexed priority queue orders the regions by their
///     cheapest merge; ties go to the lower region index;
///  5. refine_passes passes of boundary refinement: a cell next to another region whose plane it
///     lies nearer moves there;
///  6. regions under min_region_cells are dropped (their cells become -1).
/// Throws InputError for an invalid config.
SegmentResult SegmentPlanes(const scan::RangeImage& range, const SegmentConfig& config = {});

/// The result of GroupObjects.
struct Grouping {
  std::vector<int> floor_or_wall;         ///< region ids removed as floors or walls
  std::vector<std::vector<int>> objects;  ///< region ids per object group (ascending)
};

/// Floor and wall removal (paper 5.1): repeatedly, the horizontal region (|n.z| > 0.95) whose
/// centroid is lowest, with no other remaining region's centroid 5 mm or more below it (regions
/// of any normal whose centroid is within 5 mm of its height are pieces of the same plane, such
/// as a strip of the table fitted tilted, and go with it), and none above an earlier floor's by
/// more than 5 mm, is a floor (a plane below all other planes,
/// the removed ones included: a lone box top left over the table is no second floor); a vertical
/// region (|n.z| < 0.1) with the largest centroid x, every other remaining region's centroid at
/// least 2 cm nearer in x and not more than 2 cm nearer than an earlier wall's, is a wall;
/// removed until none remain. The
/// remaining regions are grouped into connected objects: two regions are in one group when some
/// pair of their cells lie within config.group_reach_cells of each other in the range image with
/// 3-D points closer than config.max_group_gap_m. s must come from SegmentPlanes on range (aborts
/// on a size mismatch).
Grouping GroupObjects(const SegmentResult& s, const scan::RangeImage& range,
                      const SegmentConfig& config = {});

}  // namespace hgrasp::segment
