#pragma once
/// @file The range image's points as the segmentation's stages see them: row-major cells, each
/// point relative to a common origin (the first valid point: moment sums about it lose less to
/// cancellation), and the neighbour test that every stage applies before joining two cells.

#include <Eigen/Core>
#include <vector>

#include "scan/range_image.h"

namespace hgrasp::segment {

/// A rows x cols grid of points (m), row-major: cell i = r * cols + c.
struct CellGrid {
  int rows = 0, cols = 0;
  Eigen::Vector3d origin_W = Eigen::Vector3d::Zero();  ///< added to p to get a point in W
  std::vector<Eigen::Vector3d> p;  ///< per cell: its point in W minus origin_W; zero if invalid
  std::vector<char> valid;         ///< per cell: whether it holds a point
  double max_gap_sq = 0.0;         ///< SegmentConfig::max_neighbour_gap_m, squared (m^2)

  int size() const { return rows * cols; }
  /// Whether cells i and j are both valid and their points closer than the gap.
  bool Near(int i, int j) const {
    return valid[i] && valid[j] && (p[i] - p[j]).squaredNorm() < max_gap_sq;
  }
};

/// The grid of a non-empty range image's points in W (aborts on an empty image).
CellGrid MakeCellGrid(const scan::RangeImage& range, double max_neighbour_gap_m);

/// Calls f(j) for the 4-neighbours j of cell i inside the grid: up, down, left, right.
template <typename F>
void ForEachNeighbour(const CellGrid& g, int i, const F& f) {
  const int r = i / g.cols, c = i % g.cols;
  for (const int j : {r > 0 ? i - g.cols : -1, r + 1 < g.rows ? i + g.cols : -1, c > 0 ? i - 1 : -1,
                      c + 1 < g.cols ? i + 1 : -1}) {
    if (j >= 0) f(j);
  }
}

}  // namespace hgrasp::segment
