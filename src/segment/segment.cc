// SegmentPlanes and GroupObjects composed of their stages, one file each:
//   cell_grid      the range image's points relative to a common origin, the neighbour test
//   plane_moments  moment sums and the plane fits from them (3x3 eigensolver)
//   patch_normals  1. a plane per cell's patch
//   connectivity   2. the initial segmentation under the paper's coplanarity tests
//   fill_in        3. cells without a normal join the plane they lie on
//   merge_regions  4. region merging by boundary cost
//   refine         5. boundary refinement; 6. the regions left, small ones dropped
//   floor_wall     floor and wall removal
//   grouping       the remaining regions grouped into objects
#include "segment/segment.h"

#include <cmath>
#include <string>
#include <vector>

#include "common/error.h"
#include "segment/cell_grid.h"
#include "segment/connectivity.h"
#include "segment/fill_in.h"
#include "segment/floor_wall.h"
#include "segment/grouping.h"
#include "segment/merge_regions.h"
#include "segment/patch_normals.h"
#include "segment/plane_moments.h"
#include "segment/refine.h"

namespace hgrasp::segment {
namespace {

void CheckConfig(const SegmentConfig& c) {
  auto bad = [](const std::string& field, double v, const std::string& expected) {
    throw InputError("", "SegmentConfig." + field, std::to_string(v), expected);
  };
  if (c.patch < 3 || c.patch % 2 == 0) bad("patch", c.patch, "an odd integer >= 3");
  if (!(c.max_patch_residual_m2 > 0.0))
    bad("max_patch_residual_m2", c.max_patch_residual_m2, "> 0");
  if (!(c.alpha1 > -1.0 && c.alpha1 < 1.0)) bad("alpha1", c.alpha1, "in (-1, 1)");
  if (!(c.alpha2 > 0.0 && c.alpha2 <= 1.0)) bad("alpha2", c.alpha2, "in (0, 1]");
  if (!(c.max_merge_residual_m2 >= 0.0 && std::isfinite(c.max_merge_residual_m2)))
    bad("max_merge_residual_m2", c.max_merge_residual_m2, ">= 0 and finite");
  if (c.min_region_cells < 1) bad("min_region_cells", c.min_region_cells, ">= 1");
  if (!(c.max_neighbour_gap_m > 0.0)) bad("max_neighbour_gap_m", c.max_neighbour_gap_m, "> 0");
}

}  // namespace

SegmentResult SegmentPlanes(const scan::RangeImage& range, const SegmentConfig& config) {
  CheckConfig(config);
  SegmentResult result;
  result.rows = range.rows();
  result.cols = range.cols();
  result.labels.assign(result.rows * result.cols, -1);
  if (result.labels.empty()) return result;
  const CellGrid grid = MakeCellGrid(range, config.max_neighbour_gap_m);

  // 1. Patch normals.
  const PatchPlanes patches = PatchNormals(grid, config.patch, config.max_patch_residual_m2);
  // 2. Initial segmentation.
  InitialRegions initial = ConnectRegions(grid, patches, config.alpha1, config.alpha2);
  std::vector<int>& label = initial.label;
  std::vector<Moments> moments = RegionMoments(grid, label, initial.n_regions);
  // 3. Cells without a normal join the plane they lie on (within 3 patch-residual std).
  FillUnlabelled(grid, patches, config.patch * config.patch,
                 3.0 * std::sqrt(config.max_patch_residual_m2), &label, &moments);
  // 4. Region merging.
  const std::vector<int> merged_into =
      MergeRegions(label, grid, config.max_merge_residual_m2, &moments);
  for (int& k : label) {
    if (k >= 0) k = merged_into[k];
  }
  // 5. Boundary refinement.
  RefineBoundaries(grid, merged_into, config.refine_passes, config.min_region_cells, &label,
                   &moments);
  // 6. Final labels and regions; small regions dropped.
  CollectRegions(grid, label, merged_into, moments, config.min_region_cells, &result);
  return result;
}

Grouping GroupObjects(const SegmentResult& s, const scan::RangeImage& range,
                      const SegmentConfig& config) {
  CheckConfig(config);
  HGRASP_DEMAND(s.rows == range.rows() && s.cols == range.cols());
  HGRASP_DEMAND(static_cast<int>(s.labels.size()) == s.rows * s.cols);
  Grouping grouping;
  const std::vector<int> index_of = RegionIndexById(s.regions);
  const std::vector<char> removed = RemoveFloorsAndWalls(s.regions, &grouping.floor_or_wall);
  grouping.objects =
      GroupRegions(s, range, index_of, removed, config.group_reach_cells, config.max_group_gap_m);
  return grouping;
}

}  // namespace hgrasp::segment
