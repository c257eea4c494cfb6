#include "scan/range_image.h"

#include <algorithm>
#include <string>

#include "common/error.h"

namespace hgrasp::scan {

RangeImage::RangeImage(int rows, int cols) : rows_(rows), cols_(cols) {
  HGRASP_DEMAND_MSG(rows >= 0 && cols >= 0,
                    "RangeImage " + std::to_string(rows) + " x " + std::to_string(cols));
  cells_.resize(static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols));
}

RangeCell& RangeImage::at(int row, int col) {
  HGRASP_DEMAND(row >= 0 && row < rows_ && col >= 0 && col < cols_);
  return cells_[static_cast<std::size_t>(row) * cols_ + col];
}

const RangeCell& RangeImage::at(int row, int col) const {
  HGRASP_DEMAND(row >= 0 && row < rows_ && col >= 0 && col < cols_);
  return cells_[static_cast<std::size_t>(row) * cols_ + col];
}

int RangeImage::CountValid() const {
  return static_cast<int>(
      std::count_if(cells_.begin(), cells_.end(), [](const RangeCell& c) { return c.valid; }));
}

}  // namespace hgrasp::scan
