// Stereo calibration from a chessboard (scan/camera_calibration.h) against ground truth worked
// out by hand: corners projected through known cameras, and a board image drawn through a known
// homography.

#include "scan/camera_calibration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace hgrasp::scan {
namespace {

PinholeCamera Camera(double fx, double fy, double cx, double cy) {
  PinholeCamera c;
  c.fx = fx, c.fy = fy, c.cx = cx, c.cy = cy;
  return c;
}

Pose3 Pose(const Eigen::Vector3d& t, double rx_deg, double ry_deg, double rz_deg) {
  Pose3 X = Pose3::Identity();
  X.linear() = (Eigen::AngleAxisd(DegToRad(rz_deg), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(DegToRad(ry_deg), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(DegToRad(rx_deg), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  X.translation() = t;
  return X;
}

std::vector<cv::Point2f> Project(const PinholeCamera& cam, const Pose3& X_CB,
                                 const ChessBoard& board) {
  std::vector<cv::Point2f> uv;
  for (const cv::Point3f& p : board.CornersB()) {
    const auto px = cam.Project(X_CB * Eigen::Vector3d(p.x, p.y, p.z));
    EXPECT_TRUE(px && cam.Contains(*px));
    uv.emplace_back(static_cast<float>(px->x()), static_cast<float>(px->y()));
  }
  return uv;
}

TEST(ChessBoard, CornersRunRowByRowAboutTheCentre) {
  const ChessBoard board{4, 3, 0.02};
  const std::vector<cv::Point3f> c = board.CornersB();
  ASSERT_EQ(c.size(), 12u);
  EXPECT_FLOAT_EQ(c[0].x, -0.03f);  // (i - 1.5) * 0.02
  EXPECT_FLOAT_EQ(c[0].y, -0.02f);  // (j - 1) * 0.02
  EXPECT_FLOAT_EQ(c[1].x, -0.01f);
  EXPECT_FLOAT_EQ(c[4].x, -0.03f);  // the second row starts again at i = 0
  EXPECT_FLOAT_EQ(c[4].y, 0.0f);
  EXPECT_FLOAT_EQ(c[11].x, 0.03f);
  EXPECT_FLOAT_EQ(c[11].y, 0.02f);
  for (const cv::Point3f& p : c) EXPECT_EQ(p.z, 0.0f);
}

// Exact corners from two known cameras 0.14 m apart: the fit gives them back.
TEST(CalibrateStereo, RecoversKnownCamerasFromExactCorners) {
  const ChessBoard board{8, 6, 0.025};
  const PinholeCamera left = Camera(233.1, 232.4, 161.2, 118.3);
  const PinholeCamera right = Camera(228.6, 228.9, 157.9, 121.4);
  // CR in CL: 0.14 m to the right, verged 6 deg towards the left camera's axis.
  const Pose3 X_LR = Pose(Eigen::Vector3d(0.14, 0.002, -0.004), 0.3, -6.0, 0.2);
  std::vector<StereoView> views;
  int k = 0;
  for (double rx : {-35.0, 0.0, 35.0}) {
    for (double ry : {-30.0, 30.0}) {
      for (double dx : {-0.03, 0.05}) {
        const Pose3 X_LB = Pose(Eigen::Vector3d(0.07 + dx, 0.01 * (k % 3 - 1), 0.42), rx, ry,
                                15.0 * (k % 4) - 20.0);
        views.push_back({Project(left, X_LB, board), Project(right, X_LR.inverse() * X_LB, board)});
        ++k;
      }
    }
  }
  const StereoCalibration fit = CalibrateStereo(views, board, 320, 240);
  EXPECT_EQ(fit.views, 12);
  EXPECT_LT(fit.rms_px, 1e-3);  // float corners: 1e-5 px
  for (const auto& [got, want] : {std::pair{fit.cameras.left, left}, {fit.cameras.right, right}}) {
    EXPECT_NEAR(got.fx, want.fx, 0.01);
    EXPECT_NEAR(got.fy, want.fy, 0.01);
    EXPECT_NEAR(got.cx, want.cx, 0.01);
    EXPECT_NEAR(got.cy, want.cy, 0.01);
    EXPECT_EQ(got.width, 320);
    EXPECT_EQ(got.height, 240);
  }
  EXPECT_NEAR(fit.baseline_m, X_LR.translation().norm(), 1e-5);
  EXPECT_LT((fit.X_LR.translation() - X_LR.translation()).norm(), 1e-5);
  EXPECT_LT(Eigen::AngleAxisd(fit.X_LR.linear().transpose() * X_LR.linear()).angle(), 1e-5);
}

TEST(CalibrateStereo, RefusesTooFewViewsAndViewsMissingCorners) {
  const ChessBoard board{8, 6, 0.025};
  const PinholeCamera cam = Camera(230, 230, 159.5, 119.5);
  const StereoView v{Project(cam, Pose(Eigen::Vector3d(0, 0, 0.4), 10, 0, 0), board),
                     Project(cam, Pose(Eigen::Vector3d(-0.14, 0, 0.4), 10, 0, 0), board)};
  EXPECT_THROW(CalibrateStereo({v, v}, board, 320, 240), std::invalid_argument);
  StereoView short_view = v;
  short_view.right.pop_back();
  EXPECT_THROW(CalibrateStereo({v, v, short_view}, board, 320, 240), std::invalid_argument);
}

// A board drawn at 8x through a known homography and averaged down to 320 x 240 (each pixel
// the mean of the light on it, as a sensor's): every corner found, within a tenth of a pixel of
// where the homography puts it, and the list starts at the end nearer the top left.
TEST(FindBoardCorners, FindsEveryCornerWhereTheHomographyPutsIt) {
  const ChessBoard board{8, 6, 0.025};
  // The board plane in board units (1 = one square), the plate's corner at (-1, -1) squares
  // beyond the first square: squares (a, b) for a in 0..8, b in 0..6, black where a + b even.
  constexpr int kScale = 8;
  const cv::Size big(320 * kScale, 240 * kScale);
  // Homography from board units (square index space, corner (i, j) at (i + 1, j + 1)) to the
  // final image's pixels, a perspective view.
  const cv::Matx33d H(14.0, 3.0, 70.0,    //
                      -2.5, 13.0, 60.0,   //
                      0.004, 0.006, 1.0);
  // To the big image: u_big = (u + 0.5) * kScale - 0.5.
  const cv::Matx33d S(kScale, 0, 0.5 * kScale - 0.5, 0, kScale, 0.5 * kScale - 0.5, 0, 0, 1);
  const cv::Matx33d H_big_from_board = S * H;
  cv::Mat image_big(big, CV_8UC1);
  const cv::Matx33d board_from_big = H_big_from_board.inv();
  for (int r = 0; r < big.height; ++r) {
    auto* row = image_big.ptr<unsigned char>(r);
    for (int c = 0; c < big.width; ++c) {
      const cv::Vec3d b = board_from_big * cv::Vec3d(c, r, 1.0);
      const double x = b[0] / b[2], y = b[1] / b[2];
      const bool on_plate = x >= -1.0 && x <= board.cols + 2.0 && y >= -1.0 && y <= board.rows + 2.0;
      const bool on_squares = x >= 0 && x < board.cols + 1 && y >= 0 && y < board.rows + 1;
      const bool black = on_squares && (static_cast<int>(x) + static_cast<int>(y)) % 2 == 0;
      row[c] = !on_plate ? 90 : black ? 15 : 225;
    }
  }
  cv::Mat image;
  cv::resize(image_big, image, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
  const std::vector<cv::Point2f> found = FindBoardCorners(image, board);
  ASSERT_EQ(found.size(), 48u);
  std::vector<cv::Point2f> truth;
  for (int j = 0; j < board.rows; ++j) {
    for (int i = 0; i < board.cols; ++i) {
      const cv::Vec3d p = H * cv::Vec3d(i + 1.0, j + 1.0, 1.0);
      truth.emplace_back(static_cast<float>(p[0] / p[2]), static_cast<float>(p[1] / p[2]));
    }
  }
  // H puts corner (0, 0) nearest the image's top left: the list starts there.
  double worst = 0, sum = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const double e = std::hypot(found[k].x - truth[k].x, found[k].y - truth[k].y);
    worst = std::max(worst, e);
    sum += e;
  }
  std::printf("corners off by %.3f px on average, %.3f px at worst\n", sum / truth.size(), worst);
  EXPECT_LT(sum / truth.size(), 0.05);
  EXPECT_LT(worst, 0.1);
}

TEST(FindBoardCorners, FindsNothingWhereThereIsNoBoard) {
  cv::Mat grey(240, 320, CV_8UC1, cv::Scalar(128));
  cv::rectangle(grey, cv::Rect(100, 80, 60, 40), cv::Scalar(20), cv::FILLED);
  EXPECT_TRUE(FindBoardCorners(grey, ChessBoard{8, 6, 0.025}).empty());
}

}  // namespace
}  // namespace hgrasp::scan
