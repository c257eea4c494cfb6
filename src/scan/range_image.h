#pragma once
/// @file The scanner's output (Taylor & Kleeman, section 2): a range image with registered colour.
/// One cell per image row and stripe position, i.e. per frame of the laser sweep; each cell holds
/// the point the stripe lit on that row, in the left camera's optical frame and in W, and the
/// surface's colour in ambient light.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace hgrasp::scan {

/// One measurement: the stripe's point on one image row at one stripe position.
struct RangeCell {
  bool valid = false;
  Eigen::Vector3d p_C = Eigen::Vector3d::Zero();  ///< point in the left camera's optical frame (m)
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  ///< the same point in W (m)
  Eigen::Vector3f rgb = Eigen::Vector3f::Zero();  ///< surface colour in ambient light, 0-1
};

/// A rows x cols grid of RangeCell, row-major and contiguous. Rows are image rows (240 for the
/// PAL cameras), columns stripe positions (frames of the sweep), in the order they were taken.
class RangeImage {
 public:
  /// An image of invalid cells; rows and cols must be >= 0 (aborts otherwise).
  RangeImage(int rows, int cols);

  int rows() const { return rows_; }
  int cols() const { return cols_; }

  /// The cell at (row, col); aborts when out of range.
  RangeCell& at(int row, int col);
  const RangeCell& at(int row, int col) const;

  /// Number of valid cells.
  int CountValid() const;

  /// Laser encoder count of each column (stripe position); empty or cols() long.
  std::vector<std::int32_t> encoder_counts;

 private:
  int rows_ = 0, cols_ = 0;
  std::vector<RangeCell> cells_;  // rows_ * cols_, row-major
};

}  // namespace hgrasp::scan
