// The range image and its writers: PLY read back byte for byte, the preview's layout and colours.

#include "scan/range_io.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "scan/range_image.h"

namespace hgrasp::scan {
namespace {

namespace fs = std::filesystem;

struct PlyVertex {
  float x, y, z;
  std::uint8_t r, g, b;
};

struct Ply {
  std::vector<std::string> header;  // lines between "ply" and "end_header", exclusive
  std::vector<PlyVertex> vertices;
  std::size_t trailing_bytes = 0;  // bytes after the last vertex
};

// Reads a binary little-endian PLY of vertices x y z (float) red green blue (uchar).
Ply ReadPly(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  EXPECT_TRUE(f) << path;
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  Ply ply;
  const std::string end = "end_header\n";
  const std::size_t end_at = bytes.find(end);
  EXPECT_NE(end_at, std::string::npos);
  if (end_at == std::string::npos) return ply;
  std::istringstream head(bytes.substr(0, end_at));
  std::string line;
  std::getline(head, line);
  EXPECT_EQ(line, "ply");
  std::size_t count = 0;
  while (std::getline(head, line)) {
    ply.header.push_back(line);
    if (line.rfind("element vertex ", 0) == 0) count = std::stoul(line.substr(15));
  }
  std::size_t at = end_at + end.size();
  for (std::size_t i = 0; i < count && at + 15 <= bytes.size(); ++i, at += 15) {
    PlyVertex v;
    float xyz[3];
    for (int k = 0; k < 3; ++k) {
      std::uint32_t u = 0;
      for (int b = 0; b < 4; ++b)
        u |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + 4 * k + b]))
             << (8 * b);
      std::memcpy(&xyz[k], &u, 4);
    }
    v.x = xyz[0], v.y = xyz[1], v.z = xyz[2];
    v.r = static_cast<std::uint8_t>(bytes[at + 12]);
    v.g = static_cast<std::uint8_t>(bytes[at + 13]);
    v.b = static_cast<std::uint8_t>(bytes[at + 14]);
    ply.vertices.push_back(v);
  }
  EXPECT_EQ(ply.vertices.size(), count) << "file shorter than its header says";
  ply.trailing_bytes = bytes.size() - at;
  return ply;
}

RangeCell Cell(const Eigen::Vector3d& p_C, const Eigen::Vector3d& p_W, const Eigen::Vector3f& rgb) {
  RangeCell c;
  c.valid = true;
  c.p_C = p_C;
  c.p_W = p_W;
  c.rgb = rgb;
  return c;
}

// A 3 x 4 image with three valid cells; (0, 1) is red and nearest, (2, 3) farthest.
RangeImage SmallImage() {
  RangeImage r(3, 4);
  r.at(0, 1) = Cell({0.0, 0.0, 0.30}, {0.31, -0.02, 0.015}, {1.0f, 0.0f, 0.0f});
  r.at(1, 2) = Cell({0.01, 0.02, 0.40}, {0.123456789, 0.1, -1e-3}, {0.2f, 0.5f, 0.7f});
  r.at(2, 3) = Cell({0.0, 0.1, 0.55}, {0.6, 0.15, 0.2}, {1.2f, -0.1f, 0.999f});  // out of 0-1
  r.encoder_counts = {-20, -10, 0, 10};
  return r;
}

std::string TempPath(const std::string& name) {
  return (fs::path(::testing::TempDir()) / name).string();
}

TEST(RangeImageTest, StartsInvalidAndCountsValidCells) {
  RangeImage r(240, 7);
  EXPECT_EQ(r.rows(), 240);
  EXPECT_EQ(r.cols(), 7);
  EXPECT_EQ(r.CountValid(), 0);
  EXPECT_FALSE(r.at(239, 6).valid);
  r.at(239, 6).valid = true;
  r.at(0, 0).valid = true;
  EXPECT_EQ(r.CountValid(), 2);
  const RangeImage& cr = r;
  EXPECT_TRUE(cr.at(239, 6).valid);
  EXPECT_FALSE(cr.at(0, 1).valid);
  EXPECT_EQ(SmallImage().CountValid(), 3);
}

TEST(RangeImageDeathTest, OutOfRangeCellAborts) {
  RangeImage r(2, 3);
  EXPECT_DEATH(r.at(2, 0), "");
  EXPECT_DEATH(r.at(0, -1), "");
}

TEST(RangeIoTest, PlyHoldsTheValidCellsInOrder) {
  const RangeImage r = SmallImage();
  const std::string path = TempPath("small.ply");
  WritePly(r, path);
  const Ply ply = ReadPly(path);
  ASSERT_GE(ply.header.size(), 8u);
  EXPECT_EQ(ply.header.front(), "format binary_little_endian 1.0");
  std::vector<std::string> no_comments;
  for (const std::string& l : ply.header)
    if (l.rfind("comment", 0) != 0) no_comments.push_back(l);
  EXPECT_EQ(no_comments, (std::vector<std::string>{
                             "format binary_little_endian 1.0", "element vertex 3",
                             "property float x", "property float y", "property float z",
                             "property uchar red", "property uchar green", "property uchar blue"}));
  ASSERT_EQ(ply.vertices.size(), 3u);
  EXPECT_EQ(ply.trailing_bytes, 0u);
  // Row-major cell order: (0, 1), (1, 2), (2, 3).
  const std::vector<std::pair<int, int>> cells = {{0, 1}, {1, 2}, {2, 3}};
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const Eigen::Vector3d& p = r.at(cells[i].first, cells[i].second).p_W;
    EXPECT_EQ(ply.vertices[i].x, static_cast<float>(p.x())) << i;
    EXPECT_EQ(ply.vertices[i].y, static_cast<float>(p.y())) << i;
    EXPECT_EQ(ply.vertices[i].z, static_cast<float>(p.z())) << i;
  }
  EXPECT_EQ(ply.vertices[0].r, 255);
  EXPECT_EQ(ply.vertices[0].g, 0);
  EXPECT_EQ(ply.vertices[0].b, 0);
  EXPECT_EQ(ply.vertices[1].r, 51);   // 0.2 * 255
  EXPECT_EQ(ply.vertices[1].g, 128);  // 127.5 rounds up
  EXPECT_EQ(ply.vertices[1].b, 179);  // 178.5 rounds up
  EXPECT_EQ(ply.vertices[2].r, 255);  // clamped
  EXPECT_EQ(ply.vertices[2].g, 0);    // clamped
  EXPECT_EQ(ply.vertices[2].b, 255);  // 254.745
  EXPECT_FALSE(fs::exists(path + ".part"));
}

TEST(RangeIoTest, EmptyImageGivesAPlyWithNoVertices) {
  const std::string path = TempPath("empty.ply");
  WritePly(RangeImage(240, 5), path);
  const Ply ply = ReadPly(path);
  EXPECT_TRUE(ply.vertices.empty());
  EXPECT_EQ(ply.trailing_bytes, 0u);
  EXPECT_NE(std::find(ply.header.begin(), ply.header.end(), "element vertex 0"), ply.header.end());
}

TEST(RangeIoTest, UnwritablePathThrowsAndLeavesNothing) {
  const std::string path = TempPath("no_such_dir/range.ply");
  try {
    WritePly(SmallImage(), path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_THROW(WriteRangePng(SmallImage(), TempPath("no_such_dir/range.png")), std::runtime_error);
}

TEST(RangeIoTest, PreviewShowsColourLeftAndRangeRightScaledByTwo) {
  const RangeImage r = SmallImage();
  const cv::Mat p = RangePreview(r);
  ASSERT_EQ(p.type(), CV_8UC3);
  ASSERT_EQ(p.rows, 2 * r.rows());
  ASSERT_EQ(p.cols, 4 * r.cols());
  const int right = 2 * r.cols();
  // Every pixel of a cell's 2 x 2 block, in either half.
  auto block = [&](int row, int col, int x0) {
    std::vector<cv::Vec3b> px;
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) px.push_back(p.at<cv::Vec3b>(2 * row + dy, x0 + 2 * col + dx));
    return px;
  };
  for (int row = 0; row < r.rows(); ++row)
    for (int col = 0; col < r.cols(); ++col) {
      if (r.at(row, col).valid) continue;
      for (int x0 : {0, right})
        for (const cv::Vec3b& v : block(row, col, x0))
          EXPECT_EQ(v, cv::Vec3b(0, 0, 0)) << row << "," << col << " x0 " << x0;
    }
  // The red cell is red (BGR) on the left.
  for (const cv::Vec3b& v : block(0, 1, 0)) EXPECT_EQ(v, cv::Vec3b(0, 0, 255));
  for (const cv::Vec3b& v : block(1, 2, 0)) EXPECT_EQ(v, cv::Vec3b(179, 128, 51));
  // Range: the nearest cell is red, the farthest blue, the middle one neither black.
  for (const cv::Vec3b& v : block(0, 1, right)) {
    EXPECT_GT(v[2], 100);
    EXPECT_LT(v[0], 20);
  }
  for (const cv::Vec3b& v : block(2, 3, right)) {
    EXPECT_GT(v[0], 100);
    EXPECT_LT(v[2], 20);
  }
  for (const cv::Vec3b& v : block(1, 2, right)) EXPECT_NE(v, cv::Vec3b(0, 0, 0));
}

TEST(RangeIoTest, PreviewOfAllInvalidIsBlack) {
  const cv::Mat p = RangePreview(RangeImage(4, 3));
  ASSERT_EQ(p.size(), cv::Size(12, 8));
  EXPECT_EQ(cv::countNonZero(p.reshape(1)), 0);
}

TEST(RangeIoTest, PngIsThePreview) {
  const RangeImage r = SmallImage();
  const std::string path = TempPath("range.png");
  WriteRangePng(r, path);
  const cv::Mat back = cv::imread(path, cv::IMREAD_COLOR);
  const cv::Mat p = RangePreview(r);
  ASSERT_EQ(back.size(), p.size());
  EXPECT_EQ(cv::norm(back, p, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace hgrasp::scan
