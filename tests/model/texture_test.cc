#include "model/texture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "common/error.h"
#include "common/geometry.h"
#include "tests/model/textured_box_scene.h"

namespace hgrasp::model {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;
using testing::TexturedBoxScene;

const FaceTexture* FindFace(const std::vector<FaceTexture>& t, int face) {
  for (const FaceTexture& f : t) {
    if (f.face == face) return &f;
  }
  return nullptr;
}

/// Expects texel (col, row) to be rgb (0-1) within one grey level per channel.
void ExpectTexel(const cv::Mat& image, int col, int row, const Vector3f& rgb) {
  const cv::Vec3b bgr = image.at<cv::Vec3b>(row, col);
  const Eigen::Vector3f got(bgr[2], bgr[1], bgr[0]);
  EXPECT_LT((got - 255.0f * rgb).cwiseAbs().maxCoeff(), 1.01f)
      << "texel (" << col << ", " << row << ") is " << got.transpose() << ", expected "
      << (255.0f * rgb).transpose();
}

TEST(FaceCorners, TexturesAreUnmirroredSeenFromOutsideWithUpOnTop) {
  const TexturedBoxScene scene;
  const BoxModel& box = scene.box;
  const Eigen::Matrix3d R_WO = box.X_WO.linear();
  const Vector3d centre = box.X_WO.translation();
  for (int f = 0; f < 6; ++f) {
    SCOPED_TRACE("face " + std::to_string(f));
    const std::array<Vector3d, 4> c = FaceCorners(box, f);
    const Vector3d n = FaceNormal(box, f);
    // The outward normal is an axis of O, pointing from the centre to the face.
    EXPECT_NEAR(n.norm(), 1.0, 1e-12);
    EXPECT_GT((0.25 * (c[0] + c[1] + c[2] + c[3]) - centre).dot(n), 0.02);
    // A camera outside looking at the face (along -n) with x right (corner 0 -> 1) and y down
    // (corner 0 -> 3) has z = x cross y along its viewing direction -n: not mirrored.
    const Vector3d right = c[1] - c[0], down = c[3] - c[0];
    EXPECT_NEAR(right.dot(down), 0.0, 1e-12);
    EXPECT_GT(right.normalized().cross(down.normalized()).dot(-n), 1.0 - 1e-9);
    EXPECT_LT((c[2] - c[1] - down).norm(), 1e-12);
    // Side faces show +z_O up.
    if (f < 4) {
      EXPECT_GT((-down).normalized().dot(R_WO.col(2)), 1.0 - 1e-9);
    }
    // The top is a plan view: x_O right, y_O up.
    if (f == 4) {
      EXPECT_GT(right.normalized().dot(R_WO.col(0)), 1.0 - 1e-9);
      EXPECT_GT((-down).normalized().dot(R_WO.col(1)), 1.0 - 1e-9);
    }
    // The indices name the same corners.
    const std::array<int, 4> idx = FaceCornerIndices(f);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(c[k], box.vertices_W[idx[k]]);
  }
}

TEST(FaceOfNormal, AxesWithinThirtyDegrees) {
  const TexturedBoxScene scene;
  const BoxModel& box = scene.box;
  const Eigen::Matrix3d R = box.X_WO.linear();
  EXPECT_EQ(FaceOfNormal(box, R.col(0)), 0);
  EXPECT_EQ(FaceOfNormal(box, -R.col(0)), 1);
  EXPECT_EQ(FaceOfNormal(box, 3.0 * R.col(1)), 2);  // any length
  EXPECT_EQ(FaceOfNormal(box, -R.col(1)), 3);
  EXPECT_EQ(FaceOfNormal(box, Vector3d::UnitZ()), 4);
  EXPECT_EQ(FaceOfNormal(box, -Vector3d::UnitZ()), 5);
  // 25 deg off -y_O towards +z_O is still face 3; 35 deg is none; between two axes is none.
  auto tilted = [&](double deg) {
    return Vector3d(-std::cos(DegToRad(deg)) * R.col(1) + std::sin(DegToRad(deg)) * R.col(2));
  };
  EXPECT_EQ(FaceOfNormal(box, tilted(25)), 3);
  EXPECT_EQ(FaceOfNormal(box, tilted(35)), -1);
  EXPECT_EQ(FaceOfNormal(box, R.col(0) + R.col(1)), -1);
  EXPECT_EQ(FaceOfNormal(box, Vector3d::Zero()), -1);
}

TEST(MakeFaceTextures, TopAndSideFromColouredCells) {
  const TexturedBoxScene scene;
  const int size = 64;
  const std::vector<FaceTexture> t = MakeFaceTextures(scene.box, scene.segments, scene.range, size);
  // Top (4) and side -y_O (3), whose region normal points into the box; regions 3 and 4 (both
  // on the top) are pooled, the table (region 9) and the unknown id 42 are ignored.
  ASSERT_EQ(t.size(), 2u);
  const FaceTexture* top = FindFace(t, 4);
  const FaceTexture* side = FindFace(t, 3);
  ASSERT_NE(top, nullptr);
  ASSERT_NE(side, nullptr);
  EXPECT_EQ(top->region, 3);  // the larger of the two
  EXPECT_EQ(side->region, 7);
  for (const FaceTexture* f : {top, side}) {
    EXPECT_EQ(f->image.type(), CV_8UC3);
    EXPECT_EQ(f->image.rows, size);
    EXPECT_EQ(f->image.cols, size);
    EXPECT_GT(f->coverage, 0.9);
    EXPECT_LE(f->coverage, 1.0);
  }
  // The side's hole (20 mm across) stays uncovered, the top has none.
  EXPECT_DOUBLE_EQ(top->coverage, 1.0);
  EXPECT_LT(side->coverage, 0.98);

  // Top, a plan view with x_O right and y_O up: red left (x_O < 0), green right, a blue band at
  // the image top (y_O > 0.02 m).
  ExpectTexel(top->image, size / 4, size * 5 / 8, TexturedBoxScene::kRed);
  ExpectTexel(top->image, size * 3 / 4, size * 5 / 8, TexturedBoxScene::kGreen);
  ExpectTexel(top->image, size / 2, 3, TexturedBoxScene::kBlue);
  ExpectTexel(top->image, 0, size - 1, TexturedBoxScene::kRed);  // the corner texels
  ExpectTexel(top->image, size - 1, size - 1, TexturedBoxScene::kGreen);

  // Side -y_O seen from outside: x_O right, z_O up: blue left, yellow right, white at the bottom,
  // the hole in the yellow (x_O 0.01-0.02 m, z_O 0.015-0.025 m) shows the face's median colour.
  ExpectTexel(side->image, size / 4, size / 2, TexturedBoxScene::kBlue);
  ExpectTexel(side->image, size * 7 / 8, size / 2, TexturedBoxScene::kYellow);
  ExpectTexel(side->image, size / 2, size - 3, TexturedBoxScene::kWhite);
  const int hole_col = static_cast<int>(std::lround((0.015 + 0.03) / 0.06 * (size - 1)));
  const int hole_row = static_cast<int>(std::lround((0.05 - 0.02) / 0.10 * (size - 1)));
  ExpectTexel(side->image, hole_col, hole_row, scene.SideMedian());
}

TEST(MakeFaceTextures, EveryTexelMatchesTheColourOfItsPointOnTheFace) {
  // Independent of the texture layout: texel (i, j) shows the point c0 + i / (size - 1) (c1 - c0)
  // + j / (size - 1) (c3 - c0) of FaceCorners; where the scene paints all four grid samples
  // around that point alike, the texel has that colour.
  const TexturedBoxScene scene;
  const int size = 48;
  const std::vector<FaceTexture> t = MakeFaceTextures(scene.box, scene.segments, scene.range, size);
  int checked = 0;
  for (const FaceTexture& f : t) {
    const std::array<Vector3d, 4> c = FaceCorners(scene.box, f.face);
    for (int j = 0; j < size; ++j) {
      for (int i = 0; i < size; ++i) {
        const Vector3d p_W =
            c[0] + (c[1] - c[0]) * i / (size - 1.0) + (c[3] - c[0]) * j / (size - 1.0);
        const std::optional<Vector3f> rgb = scene.UniformColourAround(f.face, p_W);
        if (!rgb) continue;
        ExpectTexel(f.image, i, j, *rgb);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, size * size);  // most texels of both faces
}

TEST(MakeFaceTextures, LongTrianglesAreSkippedAndBadInputThrows) {
  const TexturedBoxScene scene;
  // With max_edge_m below the 5 mm grid step no triangle is kept: all texels are the median.
  const std::vector<FaceTexture> t =
      MakeFaceTextures(scene.box, scene.segments, scene.range, 16, 0.004);
  ASSERT_EQ(t.size(), 2u);
  for (const FaceTexture& f : t) EXPECT_EQ(f.coverage, 0.0);
  const FaceTexture* side = FindFace(t, 3);
  ASSERT_NE(side, nullptr);
  ExpectTexel(side->image, 8, 8, scene.SideMedian());
  EXPECT_THROW(MakeFaceTextures(scene.box, scene.segments, scene.range, 1), InputError);
  EXPECT_THROW(MakeFaceTextures(scene.box, scene.segments, scene.range, 64, 0.0), InputError);
  BoxModel flat = scene.box;
  flat.size_O.z() = 0;
  EXPECT_THROW(MakeFaceTextures(flat, scene.segments, scene.range), InputError);
}

TEST(MakeFaceTextures, RegionsOffTheBoxAxesOrNotInTheBoxAreIgnored) {
  TexturedBoxScene scene;
  // Tilt the side region's normal 45 deg: no face; drop the top regions from the box.
  segment::PlaneRegion& side =
      *std::find_if(scene.segments.regions.begin(), scene.segments.regions.end(),
                    [](const segment::PlaneRegion& r) { return r.id == 7; });
  side.normal_W = (side.normal_W + Vector3d::UnitZ()).normalized();
  scene.box.regions = {3, 7};
  const std::vector<FaceTexture> t = MakeFaceTextures(scene.box, scene.segments, scene.range);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].face, 4);
  EXPECT_EQ(t[0].region, 3);
  scene.box.regions = {};
  EXPECT_TRUE(MakeFaceTextures(scene.box, scene.segments, scene.range).empty());
}

}  // namespace
}  // namespace hgrasp::model
