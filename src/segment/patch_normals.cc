#include "segment/patch_normals.h"

#include <algorithm>

#include "segment/plane_moments.h"

namespace hgrasp::segment {

PatchPlanes PatchNormals(const CellGrid& grid, int patch, double max_residual_m2) {
  const int rows = grid.rows, cols = grid.cols;
  const std::vector<Eigen::Vector3d>& p = grid.p;
  const std::vector<char>& valid = grid.valid;
  PatchPlanes out;
  out.normal.assign(grid.size(), Eigen::Vector3d::Zero());
  out.mean.assign(grid.size(), Eigen::Vector3d::Zero());
  out.has_normal.assign(grid.size(), 0);

  constexpr int kCh = 10;  // channels of Moments::v
  const int half = patch / 2;
  const int min_points = std::max(3, (patch * patch + 1) / 2);
  // Rows of cells' moments (kCh values per cell), with `half` empty cells on either side.
  const int width = (cols + 2 * half) * kCh;
  const int ring_rows = patch + 1;  // the window's rows and the one that just left it
  std::vector<double> ring(static_cast<size_t>(ring_rows) * width, 0.0);
  std::vector<double> column(width, 0.0);  // per cell: sums over the window's rows
  auto ring_row = [&](int r) { return &ring[static_cast<size_t>(r % ring_rows) * width]; };
  // Adds row r (sign +1) to the column sums, or removes it (-1); fills its ring row first.
  auto add_row = [&](int r, double sign) {
    double* __restrict row = ring_row(r);
    if (sign > 0.0) {
      for (int c = 0; c < cols; ++c) {
        const int i = r * cols + c;
        Moments m;
        if (valid[i]) m.Add(p[i]);
        std::copy(m.v.begin(), m.v.end(), row + (c + half) * kCh);
      }
    }
    double* __restrict sum = column.data();
    for (int k = 0; k < width; ++k) sum[k] += sign * row[k];
  };
  for (int r = 0; r < std::min(half, rows); ++r) add_row(r, 1.0);
  for (int r = 0; r < rows; ++r) {
    if (r + half < rows) add_row(r + half, 1.0);
    if (r - half - 1 >= 0) add_row(r - half - 1, -1.0);
    double win[kCh] = {};  // sums over the window of cell (r, c)
    for (int k = 0; k < patch - 1; ++k) {
      for (int ch = 0; ch < kCh; ++ch) win[ch] += column[k * kCh + ch];
    }
    for (int c = 0; c < cols; ++c) {
      const double* enter = &column[(c + patch - 1) * kCh];
      for (int ch = 0; ch < kCh; ++ch) win[ch] += enter[ch];
      if (c > 0) {
        const double* leave = &column[(c - 1) * kCh];
        for (int ch = 0; ch < kCh; ++ch) win[ch] -= leave[ch];
      }
      const int i = r * cols + c;
      if (!valid[i] || win[0] < min_points) continue;
      const Sym3 cov = Covariance(win, 1.0 / win[0]);
      const double residual = SmallestEigenvalue(cov, 0.0, max_residual_m2);
      if (residual > max_residual_m2) continue;
      out.normal[i] = SmallestEigenvector(cov, residual);
      out.mean[i] = Eigen::Vector3d(win[1], win[2], win[3]) / win[0];
      out.has_normal[i] = 1;
    }
  }
  return out;
}

}  // namespace hgrasp::segment
