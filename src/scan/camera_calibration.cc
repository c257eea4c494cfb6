#include "scan/camera_calibration.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "scan/scanner.h"

namespace hgrasp::scan {

std::vector<cv::Point3f> ChessBoard::CornersB() const {
  std::vector<cv::Point3f> corners;
  corners.reserve(static_cast<std::size_t>(cols) * rows);
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      corners.emplace_back(static_cast<float>((i - 0.5 * (cols - 1)) * square_m),
                           static_cast<float>((j - 0.5 * (rows - 1)) * square_m), 0.0f);
    }
  }
  return corners;
}

std::vector<cv::Point2f> FindBoardCorners(const cv::Mat& image, const ChessBoard& board) {
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = image;
  }
  const cv::Size pattern(board.cols, board.rows);
  // The detector wants squares of a dozen pixels and more; at 320 x 240 a board's squares are
  // 8-20 px, so it looks at the image magnified 2x (pixel centres: u = (u2 + 0.5) / 2 - 0.5).
  // OpenCV's sector-based detector (findChessboardCornersSB) with CALIB_CB_ACCURACY fits each
  // corner to the image around it: on the twin's boards at 4 samples a pixel its corners are
  // 0.05-0.15 px RMS from the true ones where findChessboardCorners with cornerSubPix (a 7 px
  // window, under half the spacing of the corners) was 0.09-0.23 px
  // (tests/scan/board_corners_test.cc).
  cv::Mat big;
  cv::resize(grey, big, cv::Size(), 2.0, 2.0, cv::INTER_LINEAR);
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCornersSB(big, pattern, corners,
                                   cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY) ||
      corners.size() != static_cast<std::size_t>(board.cols * board.rows)) {
    return {};
  }
  for (cv::Point2f& c : corners) {
    c = cv::Point2f(0.5f * (c.x + 0.5f) - 0.5f, 0.5f * (c.y + 0.5f) - 0.5f);
  }
  // Half a turn of the board gives the same picture: start at the end nearer the top left.
  if (corners.front().x + corners.front().y > corners.back().x + corners.back().y) {
    std::reverse(corners.begin(), corners.end());
  }
  return corners;
}

StereoCalibration CalibrateStereo(const std::vector<StereoView>& views, const ChessBoard& board,
                                  int width, int height) {
  if (views.size() < 3) {
    throw std::invalid_argument("CalibrateStereo: at least 3 views, got " +
                                std::to_string(views.size()));
  }
  const std::size_t n = static_cast<std::size_t>(board.cols * board.rows);
  std::vector<std::vector<cv::Point3f>> object(views.size(), board.CornersB());
  std::vector<std::vector<cv::Point2f>> left, right;
  for (const StereoView& v : views) {
    if (v.left.size() != n || v.right.size() != n) {
      throw std::invalid_argument("CalibrateStereo: a view without every corner of the board");
    }
    left.push_back(v.left);
    right.push_back(v.right);
  }
  const cv::Size size(width, height);
  // Ideal pinholes (robot::StereoIntrinsics): the distortion stays zero.
  const int flags = cv::CALIB_FIX_K1 | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3 |
                    cv::CALIB_ZERO_TANGENT_DIST;
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12);
  cv::Mat K[2], D[2];
  for (int c = 0; c < 2; ++c) {
    D[c] = cv::Mat::zeros(1, 5, CV_64F);
    K[c] = cv::Mat::eye(3, 3, CV_64F);
    std::vector<cv::Mat> rvecs, tvecs;
    cv::calibrateCamera(object, c == 0 ? left : right, size, K[c], D[c], rvecs, tvecs, flags,
                        criteria);
  }
  cv::Mat R, T, E, F;
  StereoCalibration out;
  out.rms_px = cv::stereoCalibrate(object, left, right, K[0], D[0], K[1], D[1], size, R, T, E, F,
                                   flags | cv::CALIB_USE_INTRINSIC_GUESS, criteria);
  out.views = static_cast<int>(views.size());
  for (int c = 0; c < 2; ++c) {
    PinholeCamera& cam = c == 0 ? out.cameras.left : out.cameras.right;
    cam.width = width;
    cam.height = height;
    cam.fx = K[c].at<double>(0, 0);
    cam.fy = K[c].at<double>(1, 1);
    cam.cx = K[c].at<double>(0, 2);
    cam.cy = K[c].at<double>(1, 2);
  }
  // stereoCalibrate's R, T carry a point from CL to CR: X_RL.
  Pose3 X_RL = Pose3::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X_RL.linear()(r, c) = R.at<double>(r, c);
    X_RL.translation()[r] = T.at<double>(r, 0);
  }
  out.X_LR = X_RL.inverse();
  out.baseline_m = out.X_LR.translation().norm();
  return out;
}

namespace {

void SaveView(const std::string& dir, int index, const cv::Mat& image, const char* side,
              const ChessBoard& board, const std::vector<cv::Point2f>& corners) {
  cv::Mat out = image.clone();
  if (!corners.empty()) {
    cv::drawChessboardCorners(out, cv::Size(board.cols, board.rows), corners, true);
  }
  char name[64];
  std::snprintf(name, sizeof name, "view_%02d_%s.png", index, side);
  const std::string path = (std::filesystem::path(dir) / name).string();
  if (!cv::imwrite(path, out)) throw std::runtime_error("cannot write " + path);
}

}  // namespace

bool CalibrateCameras(device::RobotDevices& dev, const CameraCalibrationConfig& config,
                      CameraCalibrationReport* report) {
  *report = CameraCalibrationReport{};
  const auto fail = [&](device::Status status, const std::string& device,
                        const std::string& what) {
    report->status = status;
    report->failed_device = device;
    report->failure = what;
    return false;
  };
  // The stripe would cross the board's squares.
  if (const auto st = dev.laser->SetLaser(false); st != device::Status::kOk) {
    return fail(st, "laser", "laser: " + std::string(device::ToString(st)) + " switching it off");
  }
  if (!config.views_dir.empty()) std::filesystem::create_directories(config.views_dir);
  std::vector<StereoView> views;
  int width = 0, height = 0;
  for (std::size_t i = 0; i < config.head_poses.size(); ++i) {
    std::string failed;
    const device::Status moved = MoveHeadForScan(dev, config.head_poses[i], config.stop, &failed);
    if (moved != device::Status::kOk) {
      return fail(moved, failed,
                  moved == device::Status::kInterrupted
                      ? "interrupted"
                      : failed + ": " + std::string(device::ToString(moved)) +
                            " moving the head to pose " + std::to_string(i));
    }
    device::StereoFrame frame;
    if (const auto st = dev.cameras->Grab(&frame); st != device::Status::kOk) {
      return fail(st, "cameras", "cameras: " + std::string(device::ToString(st)) + " grabbing");
    }
    ++report->poses;
    width = frame.left.cols;
    height = frame.left.rows;
    StereoView view;
    view.left = FindBoardCorners(frame.left, config.board);
    view.right = FindBoardCorners(frame.right, config.board);
    // Both cameras list the same corner first: the board's rows run the same way in both.
    if (!view.left.empty() && !view.right.empty()) {
      const cv::Point2f dl = view.left.back() - view.left.front();
      const cv::Point2f dr = view.right.back() - view.right.front();
      if (dl.dot(dr) < 0) std::reverse(view.right.begin(), view.right.end());
    }
    if (!config.views_dir.empty()) {
      SaveView(config.views_dir, static_cast<int>(i), frame.left, "left", config.board, view.left);
      SaveView(config.views_dir, static_cast<int>(i), frame.right, "right", config.board,
               view.right);
    }
    if (view.left.empty() || view.right.empty()) {
      report->missed.push_back(static_cast<int>(i));
      continue;
    }
    views.push_back(std::move(view));
    report->view_joints.push_back(frame.head);
  }
  report->views_used = static_cast<int>(views.size());
  if (report->views_used < std::max(3, config.min_views)) {
    return fail(device::Status::kOk, "",
                "the board was found by both cameras in " + std::to_string(report->views_used) +
                    " of " + std::to_string(report->poses) + " views; at least " +
                    std::to_string(std::max(3, config.min_views)) + " needed");
  }
  report->fit = CalibrateStereo(views, config.board, width, height);
  if (!(report->fit.rms_px <= config.max_rms_px)) {
    char what[160];
    std::snprintf(what, sizeof what,
                  "the reprojection RMS is %.3f px, above the accepted %.3f px (corners found "
                  "wrongly, or a board that moved?)",
                  report->fit.rms_px, config.max_rms_px);
    return fail(device::Status::kOk, "", what);
  }
  return true;
}

}  // namespace hgrasp::scan
