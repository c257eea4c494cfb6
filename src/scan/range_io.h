#pragma once
/// @file Writers for a RangeImage: the point cloud as PLY (DESIGN.md, "range.ply") and a preview
/// image for people after Taylor & Kleeman's Figure 4 (registered colour beside range).

#include <opencv2/core.hpp>
#include <string>

#include "scan/range_image.h"

namespace hgrasp::scan {

/// Writes the valid cells of `r` as a binary_little_endian PLY: one vertex per valid cell, in
/// row-major cell order, with properties x y z (float, p_W in m) and red green blue (uchar, rgb
/// scaled to 0-255 and rounded). The file appears whole or not at all (written beside `path`
/// and renamed). Throws std::runtime_error naming the path when it cannot be written.
void WritePly(const RangeImage& r, const std::string& path);

/// A preview like Taylor & Kleeman's Figure 4, CV_8UC3 BGR, 2 rows() x 4 cols(): the left half
/// shows each cell's registered colour, the right half its range |p_C| in false colour (near red,
/// far blue, scaled between the nearest and farthest valid cell); invalid cells are black in both.
/// Each cell is drawn as a 2 x 2 block (nearest-neighbour) so that it is legible.
cv::Mat RangePreview(const RangeImage& r);

/// Writes RangePreview(r) as a PNG to `path`, whole or not at all. Throws std::runtime_error
/// naming the path when it cannot be written or `r` has no cells.
void WriteRangePng(const RangeImage& r, const std::string& path);

}  // namespace hgrasp::scan
