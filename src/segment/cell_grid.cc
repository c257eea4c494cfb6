#include "segment/cell_grid.h"

#include "common/error.h"

namespace hgrasp::segment {

CellGrid MakeCellGrid(const scan::RangeImage& range, double max_neighbour_gap_m) {
  CellGrid g;
  g.rows = range.rows();
  g.cols = range.cols();
  const int n_cells = g.size();
  HGRASP_DEMAND(n_cells > 0);
  const scan::RangeCell* const cells = &range.at(0, 0);  // row-major, contiguous
  for (int i = 0; i < n_cells; ++i) {
    if (cells[i].valid) {
      g.origin_W = cells[i].p_W;
      break;
    }
  }
  g.p.assign(n_cells, Eigen::Vector3d::Zero());
  g.valid.assign(n_cells, 0);
  for (int i = 0; i < n_cells; ++i) {
    if (!cells[i].valid) continue;
    g.valid[i] = 1;
    g.p[i] = cells[i].p_W - g.origin_W;
  }
  g.max_gap_sq = max_neighbour_gap_m * max_neighbour_gap_m;
  return g;
}

}  // namespace hgrasp::segment
