#include "scan/range_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "common/write_file.h"

namespace hgrasp::scan {
namespace {

// Colour 0-1 to 0-255, rounded and clamped.
std::uint8_t ToByte(float v) {
  if (!(v > 0.0f)) return 0;  // also NaN
  return static_cast<std::uint8_t>(std::lround(std::min(v, 1.0f) * 255.0f));
}

// Appends a float in little-endian byte order, whatever the host's.
void PutFloatLe(float f, std::vector<char>* out) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((u >> (8 * i)) & 0xff));
}

// Scales `small` up by 2 with nearest-neighbour into the `x0`-th column block of `dst`.
void PasteX2(const cv::Mat& small, cv::Mat* dst, int x0) {
  if (small.empty()) return;
  cv::Mat big;
  cv::resize(small, big, cv::Size(), 2.0, 2.0, cv::INTER_NEAREST);
  big.copyTo((*dst)(cv::Rect(x0, 0, big.cols, big.rows)));
}

}  // namespace

void WritePly(const RangeImage& r, const std::string& path) {
  const int n = r.CountValid();
  std::vector<char> body;
  body.reserve(static_cast<std::size_t>(n) * 15);
  for (int row = 0; row < r.rows(); ++row)
    for (int col = 0; col < r.cols(); ++col) {
      const RangeCell& c = r.at(row, col);
      if (!c.valid) continue;
      for (int i = 0; i < 3; ++i) PutFloatLe(static_cast<float>(c.p_W[i]), &body);
      for (int i = 0; i < 3; ++i) body.push_back(static_cast<char>(ToByte(c.rgb[i])));
    }
  const std::string header =
      "ply\n"
      "format binary_little_endian 1.0\n"
      "comment hgrasp range image: points in W (m), colour in ambient light\n"
      "element vertex " +
      std::to_string(n) +
      "\n"
      "property float x\n"
      "property float y\n"
      "property float z\n"
      "property uchar red\n"
      "property uchar green\n"
      "property uchar blue\n"
      "end_header\n";
  std::string bytes = header;
  bytes.append(body.data(), body.size());
  WriteFileWhole(path, bytes);
}

cv::Mat RangePreview(const RangeImage& r) {
  const int rows = r.rows(), cols = r.cols();
  cv::Mat colour(rows, cols, CV_8UC3, cv::Scalar::all(0));
  cv::Mat range(rows, cols, CV_8UC3, cv::Scalar::all(0));
  std::vector<double> ranges;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col)
      if (const RangeCell& c = r.at(row, col); c.valid) {
        ranges.push_back(c.p_C.norm());
        colour.at<cv::Vec3b>(row, col) =
            cv::Vec3b(ToByte(c.rgb.z()), ToByte(c.rgb.y()), ToByte(c.rgb.x()));
      }
  // The colour scale spans the 1st to 99th percentile: a stray point does not flatten it.
  double lo = 0.0, hi = 0.0;
  if (!ranges.empty()) {
    std::sort(ranges.begin(), ranges.end());
    lo = ranges[ranges.size() / 100];
    hi = ranges[ranges.size() - 1 - ranges.size() / 100];
  }
  if (hi > 0.0) {
    // Near maps to 255 (red in COLORMAP_JET), far to 0 (dark blue).
    cv::Mat grey(rows, cols, CV_8U, cv::Scalar(0));
    cv::Mat invalid(rows, cols, CV_8U, cv::Scalar(255));
    for (int row = 0; row < rows; ++row)
      for (int col = 0; col < cols; ++col)
        if (const RangeCell& c = r.at(row, col); c.valid) {
          grey.at<uchar>(row, col) =
              cv::saturate_cast<uchar>(255.0 * (hi - c.p_C.norm()) / std::max(hi - lo, 1e-9));
          invalid.at<uchar>(row, col) = 0;
        }
    cv::applyColorMap(grey, range, cv::COLORMAP_JET);
    range.setTo(cv::Scalar::all(0), invalid);
  }
  cv::Mat out(2 * rows, 4 * cols, CV_8UC3, cv::Scalar::all(0));
  PasteX2(colour, &out, 0);
  PasteX2(range, &out, 2 * cols);
  return out;
}

void WriteRangePng(const RangeImage& r, const std::string& path) {
  const cv::Mat preview = RangePreview(r);
  if (preview.empty()) throw std::runtime_error(path + ": the range image is empty");
  std::vector<uchar> png;
  if (!cv::imencode(".png", preview, png)) throw std::runtime_error(path + ": PNG encoding failed");
  WriteFileWhole(path, {reinterpret_cast<const char*>(png.data()), png.size()});
}

}  // namespace hgrasp::scan
