#pragma once
/// @file The gripper tracker (paper section 6): finds one gripper by its LEDs, identifies each LED
/// by flashing them one at a time, and then follows the gripper's pose X_CLE (E in the left
/// camera's optical frame) frame by frame through the pose Kalman filter.
///
/// Initialise (also the recovery when tracking is lost), as in the paper: all LEDs on, the filter
/// starts from the mean of the triangulated LEDs (InitialisePosition); then, per cycle, one frame
/// with all LEDs off (the background: anything bright and red that is not this gripper's LEDs)
/// and one frame per LED with only that LED on; the one new triangulated point that is not in
/// the background is that LED, whatever else is in view. The identified LEDs give a pose
/// (FitGripperPose) that the filter fuses; cycles repeat until the filter has converged or
/// max_init_cycles are spent. All LEDs are on when Initialise returns.
///
/// Track, per frame with all LEDs on: LEDs in both images -> triangulated points -> each point
/// associated to the LED whose predicted position (filter pose after Predict) is nearest, within
/// a gate -> FitGripperPose -> filter Update. Too few associated LEDs for max_missed_frames
/// frames in a row makes lost() true; the caller then runs Initialise again.

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "device/leds.h"
#include "device/stereo_camera.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/stereo_geometry.h"
#include "servo/led_detector.h"
#include "servo/led_layout.h"
#include "servo/pose_filter.h"

namespace hgrasp::servo {

struct GripperTrackerOptions {
  LedDetectorConfig detector;
  LedMatchConfig match;
  PoseFilterOptions filter;
  /// Noise of a pose measured by FitGripperPose from triangulated LEDs.
  PoseMeasurementNoise measurement;
  /// Position std dev (m) given to the filter with the LEDs' mean at start-up: the mean is not
  /// E's origin (it is off by the layout's centroid in E, a few cm).
  double initial_position_std = 0.05;
  /// At most this many flash cycles per Initialise.
  int max_init_cycles = 5;
  /// A point that moved less than this (m) between the all-off frame and a flash frame is
  /// background, not the flashed LED.
  double background_radius = 0.005;
  /// A triangulated point is associated to an LED only within this distance (m) of the LED's
  /// predicted position (the LEDs are >= 54 mm apart in the sim layout).
  double association_gate = 0.02;
  /// With more than 3 LEDs, the LED with the largest fit residual is dropped (and the pose
  /// refitted) while that residual exceeds this (m): a partly hidden LED triangulates off centre.
  double max_led_residual = 0.0015;
  /// A fitted pose whose RMS residual exceeds this (m) is rejected (a wrong association).
  double max_fit_rms = 0.004;
  /// Image-level fallback (the paper's form of measurement), used when fewer than 3 LEDs are
  /// triangulated: every blob in either image is associated to the LED whose projection through
  /// the predicted pose lies nearest, within this many pixels ...
  double image_gate_px = 8.0;
  /// ... and the pose minimising the reprojection error of at least 4 such blobs of at least 3
  /// LEDs is fused, with this pixel noise (std dev, px) ...
  double pixel_std = 1.0;
  /// ... unless its RMS reprojection error exceeds this (px).
  double max_reprojection_rms_px = 1.5;
  /// While tracking, a blob smaller than this fraction of the median area of the gripper's
  /// blobs in the same image is taken for a partly hidden LED and not used.
  double min_blob_area_ratio = 0.7;
  /// A pose measurement whose normalised innovation squared (6 dof) exceeds this is rejected.
  double max_nis = 100.0;
  /// lost() after this many frames in a row without a pose measurement (10 frames = 0.4 s).
  int max_missed_frames = 10;
  /// Error (std dev per axis) of a relative move the arm made unwatched (ExpectMove): the
  /// Puma repeats a small move to well under a millimetre; this allows for the arm's kinematic
  /// model being a little off the true arm over the move.
  PoseMeasurementNoise move_error = {0.003, 0.03};
};

enum class TrackerStatus {
  kOk = 0,
  kDeviceError,     ///< Leds::Set or StereoCamera::Grab failed (see device_status())
  kNotFound,        ///< Initialise: no LED seen, or the filter did not converge
  kNotInitialised,  ///< Track before a successful Initialise
  kNoMeasurement,   ///< Track: too few LEDs associated, or the fit was rejected
  kLost,            ///< Track: lost (too many frames without a measurement); run Initialise
};

std::string_view ToString(TrackerStatus s);

class GripperTracker {
 public:
  /// @param side     the gripper tracked (which LEDs Initialise switches)
  /// @param layout   its LED positions in E (LoadLedLayouts(...).Of(side))
  /// @param cameras  the stereo intrinsics
  /// @param head     head kinematics: the cameras' relative pose at each frame's verge angle
  /// @throws InputError for a layout with fewer than 3 or more than kMaxLeds LEDs.
  GripperTracker(device::Side side, LedLayout layout, robot::StereoIntrinsics cameras,
                 robot::HeadKinematics head, const GripperTrackerOptions& options = {});

  /// Finds and identifies the LEDs and runs the filter to convergence (see the file comment).
  /// Restarts the filter from scratch; clears lost(). Grabs 2 + Count frames per cycle.
  TrackerStatus Initialise(device::Leds& leds, device::StereoCamera& camera);

  /// One frame with all LEDs on (see the file comment). Frames must come in time order.
  TrackerStatus Track(const device::StereoFrame& frame);

  /// The cameras moved (the head turned) between frames: X_CnewC is the old camera frame seen
  /// from the new one (servo::HeadTracker::X_CnewC). Carries the filter's state into the new
  /// frame so that tracking goes on without a jump. Nothing to do before Initialise.
  void CarryThroughCameraMove(const Pose3& X_CnewC);

  /// The arm moved the gripper by X_EEnew (in its own frame, as Arm::MoveRelative is told) and
  /// is at rest at t_s, the time of the frame that showed it still; the frames of the move were
  /// not tracked. The filter's pose becomes the moved one (GripperTrackerOptions::move_error
  /// added) at rest at t_s. Tracking the move's frames instead fails where the task reads a
  /// 9600-baud arm between frames: they come 0.3 s apart, the first fuses the move's speed, and
  /// the constant-velocity prediction runs on past a gripper that has long stopped (80 mm in a
  /// twin run, and the tracker was lost). Nothing to do unless tracking().
  void ExpectMove(const Pose3& X_EEnew, double t_s);

  bool lost() const { return lost_; }
  /// True after a successful Initialise, until lost.
  bool tracking() const { return tracking_; }
  const PoseFilter& filter() const { return filter_; }
  /// X_CLE: the filter's gripper pose in the left camera's optical frame.
  Pose3 pose() const { return filter_.pose(); }
  device::Side side() const { return side_; }
  const LedLayout& layout() const { return layout_; }

  /// LED i's position in CL at the last measurement (nullopt when it was not seen/identified).
  const std::vector<std::optional<Eigen::Vector3d>>& last_leds() const { return last_leds_; }
  double last_fit_rms() const { return last_fit_rms_; }  ///< m
  double last_nis() const { return last_nis_; }
  device::Status device_status() const { return device_status_; }
  /// The device of the last call ("cameras" or "leds"): with kDeviceError, the one that failed.
  std::string_view failed_device() const { return failed_device_; }

  std::int64_t frames() const { return frames_; }              ///< frames grabbed or tracked
  std::int64_t flashes() const { return flashes_; }            ///< single-LED flash frames
  std::int64_t recoveries() const { return recoveries_; }      ///< Initialise successes after lost
  std::int64_t measurements() const { return measurements_; }  ///< poses fused
  /// Of those, poses from the image-level fallback (MeasureInImages).
  std::int64_t image_measurements() const { return image_measurements_; }

 private:
  const scan::Rectification& RectificationAt(double verge);
  std::vector<LedPoint> Points(const device::StereoFrame& frame);
  /// Predicts the filter to time t_s (never backwards).
  void PredictTo(double t_s);
  /// Fits the identified LEDs (ids[k] = LED of points[k], or -1) and fuses the pose: `first`
  /// starts the filter from it, else it is a (gated) update. True when fused.
  bool Fuse(const std::vector<LedPoint>& points, const std::vector<int>& ids, bool first);
  /// Predicts to the frame, associates its points by the predicted pose and fuses the fit; when
  /// that fails, MeasureInImages.
  bool MeasureTracked(const device::StereoFrame& frame);
  /// The image-level measurement (see GripperTrackerOptions::image_gate_px): blobs of both images
  /// against the LEDs' projections, Gauss-Newton on the reprojection error from the predicted
  /// pose, fused with the covariance pixel_std^2 (J^T J)^-1.
  bool MeasureInImages(const std::vector<LedBlob>& left, const std::vector<LedBlob>& right,
                       const std::vector<int>& in_left, const std::vector<int>& in_right,
                       double verge);
  /// For each LED, the blob nearest its projection through X_CE (within image_gate_px, one to
  /// one), or -1: `camera` at X_KCL (the camera seen from CL).
  std::vector<int> AssociateBlobs(const std::vector<LedBlob>& blobs, const PinholeCamera& camera,
                                  const Pose3& X_KCL, const Pose3& X_CE) const;
  /// The right camera's optical frame in the left one's at a verge angle.
  Pose3 X_CLCR(double verge) const;

  TrackerStatus Grab(device::StereoCamera& camera, device::StereoFrame* frame);
  /// The first frame sure to show LEDs switched just before (StereoCamera::frames_in_flight).
  TrackerStatus GrabAfterLeds(device::StereoCamera& camera, device::StereoFrame* frame);
  TrackerStatus SetLeds(device::Leds& leds, std::uint32_t mask);

  device::Side side_;
  LedLayout layout_;
  robot::StereoIntrinsics cameras_;
  robot::HeadKinematics head_;
  GripperTrackerOptions options_;
  PoseFilter filter_;

  std::optional<double> rect_verge_;
  scan::Rectification rect_;

  bool tracking_ = false;
  bool lost_ = false;
  bool has_orientation_ = false;
  double last_t_s_ = 0.0;
  int missed_ = 0;
  std::vector<std::optional<Eigen::Vector3d>> last_leds_;
  double last_fit_rms_ = 0.0;
  double last_nis_ = 0.0;
  device::Status device_status_ = device::Status::kOk;
  std::string_view failed_device_ = "cameras";
  std::int64_t frames_ = 0, flashes_ = 0, recoveries_ = 0, measurements_ = 0;
  std::int64_t image_measurements_ = 0;
};

}  // namespace hgrasp::servo
