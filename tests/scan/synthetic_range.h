#pragma once
// Synthetic range images for the segmentation and box-model tests: surfaces laid out as blocks of
// cells, and seeded noise.

#include <Eigen/Core>
#include <random>

#include "scan/range_image.h"

namespace hgrasp::scan::testing {

/// Fills rows [r0, r0 + nr) x cols [c0, c0 + nc) with points origin + (r - r0) dr + (c - c0) dc.
inline void FillBlock(RangeImage* img, int r0, int nr, int c0, int nc,
                      const Eigen::Vector3d& origin, const Eigen::Vector3d& dr,
                      const Eigen::Vector3d& dc) {
  for (int r = r0; r < r0 + nr; ++r) {
    for (int c = c0; c < c0 + nc; ++c) {
      RangeCell& cell = img->at(r, c);
      cell.valid = true;
      cell.p_W = origin + (r - r0) * dr + (c - c0) * dc;
      cell.p_C = cell.p_W;
    }
  }
}

/// Adds Gaussian noise (sigma, m, per axis) to every valid point, drawn from `seed`.
inline void AddNoise(RangeImage* img, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  for (int r = 0; r < img->rows(); ++r) {
    for (int c = 0; c < img->cols(); ++c) {
      RangeCell& cell = img->at(r, c);
      if (cell.valid) cell.p_W += Eigen::Vector3d(g(rng), g(rng), g(rng));
    }
  }
}

}  // namespace hgrasp::scan::testing
