#pragma once
/// @file Stereo camera calibration from a chessboard (`hgrasp calibrate cameras`): the head
/// looks at a board from several poses, OpenCV finds the board's inner corners in both images,
/// and a bundle adjustment (cv::calibrateCamera, then cv::stereoCalibrate over both cameras)
/// fits each camera's focal lengths and principal point and the right camera's pose in the
/// left's. The cameras file the scanner reads holds the intrinsics (robot::StereoIntrinsics: an
/// ideal pinhole, so the distortion is held at zero); the cameras' poses keep coming from the
/// head's kinematics (models/humanoid.urdf), and the fitted baseline is reported beside them.
///
/// Frames (DESIGN.md rule 4): B the board (origin at the centre of its printed face, x along
/// its cols, y along its rows, z out of the face), CL and CR the optical frames.

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include "common/geometry.h"
#include "common/stop_request.h"
#include "device/robot_devices.h"
#include "robot/calibration.h"

namespace hgrasp::scan {

/// A chessboard's printed geometry: `cols` x `rows` inner corners, squares of `square_m`.
struct ChessBoard {
  int cols = 9;
  int rows = 6;
  double square_m = 0.025;
  /// The inner corners in B, in the order FindBoardCorners returns them (row by row: corner
  /// (i, j) at index j * cols + i): ((i - (cols - 1) / 2) s, (j - (rows - 1) / 2) s, 0).
  std::vector<cv::Point3f> CornersB() const;
};

/// The inner corners of `board` in a BGR (or grey) image, refined to a fraction of a pixel
/// (cv::findChessboardCornersSB with CALIB_CB_ACCURACY on the image magnified 2x); empty when
/// the detector did not find every corner. The list starts at the corner nearest the image's
/// top left of the two ends of the board's first row or last row (a chessboard turned half a
/// turn looks the same), so that the two cameras of a stereo view list the same corner first.
std::vector<cv::Point2f> FindBoardCorners(const cv::Mat& image, const ChessBoard& board);

/// One view of the board by both cameras.
struct StereoView {
  std::vector<cv::Point2f> left, right;  ///< FindBoardCorners of each image
};

/// What a stereo calibration found.
struct StereoCalibration {
  robot::StereoIntrinsics cameras;  ///< fitted intrinsics (path empty)
  Pose3 X_LR = Pose3::Identity();   ///< CR in CL (m)
  double baseline_m = 0.0;          ///< |X_LR.translation()|
  double rms_px = 0.0;              ///< reprojection RMS over both cameras and every corner (px)
  int views = 0;                    ///< stereo views used
};

/// Fits both cameras' intrinsics and their relative pose to `views` (each with every corner of
/// `board` in both images) for images of `width` x `height` pixels: per camera
/// cv::calibrateCamera (fx, fy, cx, cy; no distortion), then cv::stereoCalibrate refining
/// everything over both cameras at once. Pixel convention of src/common/pinhole_camera.h (the
/// centre of pixel (i, j) at (i, j), which is OpenCV's).
/// @throws std::invalid_argument with fewer than 3 views or a view whose corner count is not
///         the board's.
StereoCalibration CalibrateStereo(const std::vector<StereoView>& views, const ChessBoard& board,
                                  int width, int height);

/// How `hgrasp calibrate cameras` collects its views.
struct CameraCalibrationConfig {
  ChessBoard board;
  /// Head joints to look from; each pose's frame makes one view where both cameras find the
  /// whole board (the others are counted and skipped).
  std::vector<device::HeadJoints> head_poses;
  /// Reject the calibration when the reprojection RMS is above this (px): corners found wrongly
  /// or a board that moved.
  double max_rms_px = 0.5;
  int min_views = 8;              ///< fewer usable views than this: no calibration
  std::string views_dir;          ///< non-empty: each view's images with its corners, as PNGs
  const StopRequest* stop = nullptr;
};

/// What the collection and the fit found, for the log and the report.
struct CameraCalibrationReport {
  device::Status status = device::Status::kOk;
  std::string failed_device;  ///< when a device failed: "head" or "cameras"
  std::string failure;        ///< empty when a calibration was returned
  int poses = 0;              ///< head poses visited
  int views_used = 0;         ///< of which both cameras found the whole board
  std::vector<int> missed;    ///< the poses (indices) where a camera did not
  StereoCalibration fit;      ///< valid when a calibration was returned
  /// The head joints each used view was taken at (as the frame latched them).
  std::vector<device::HeadJoints> view_joints;
};

/// Moves the head to each of config.head_poses, grabs a frame there, finds the board in both
/// images and fits the cameras (CalibrateStereo). Returns false (report says why) when a device
/// fails, a stop is requested, too few views saw the board or the RMS is above max_rms_px.
bool CalibrateCameras(device::RobotDevices& dev, const CameraCalibrationConfig& config,
                      CameraCalibrationReport* report);

}  // namespace hgrasp::scan
