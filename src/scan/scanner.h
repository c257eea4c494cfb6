#pragma once
/// @file The laser scanner: sweeps the stripe across the scene through the device seam and
/// turns the frames into a RangeImage with registered colour; and the laser's self-calibration.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "common/stop_request.h"
#include "device/robot_devices.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/range_image.h"
#include "scan/stripe_frame.h"

namespace hgrasp::scan {

/// Where the head looks for a scan: both optical axes through the workspace's centre
/// (0.30, 0, 0.05) m in W, as models/humanoid.xml's keyframe "home" (pan 0, tilt 41.390 deg,
/// verge 6.693 deg). A real Biclops ends its homing at its index marks, looking ahead.
inline constexpr device::HeadJoints kLookHead{0.0, 0.72238375471590055, 0.11681727844879244};

/// Moves the head to `q` unless it stands within `tolerance_rad` of it on every axis, then
/// waits with frames (grabbed without images) until it is still and `settle_frames` more.
/// kOk, or the status that ended it with *failed_device ("head", "cameras"; "" for a stop
/// request: kInterrupted); kTimeout when the head has not stopped after `timeout_frames`.
device::Status MoveHeadForScan(device::RobotDevices& dev, const device::HeadJoints& q,
                               const StopRequest* stop, std::string* failed_device,
                               double tolerance_rad = 0.1 * kPi / 180.0, int settle_frames = 4,
                               int timeout_frames = 250);

/// The sweep: from start to end count in `positions` frames (one stripe position per frame).
/// Left to right as the cameras see it, so that the range image's columns read like the images.
struct SweepConfig {
  std::int32_t start_count = 2400;  ///< +24 deg: the workspace's left edge and beyond
  std::int32_t end_count = -2400;   ///< -24 deg: its right edge
  int positions = 300;              ///< 12 s at 25 frames/s
  /// Polled at every frame: when requested the sweep ends with Status::kInterrupted (the
  /// caller leaves the robot safe). May be null.
  const StopRequest* stop = nullptr;
  /// Start from a laser at rest: after the board says the slew to the start has ended, wait until
  /// its encoder holds still over a frame. A motor's servo lags its profile (the twin's laser was
  /// 260 counts short of a 9000 counts/s slew's end when its board said it had stopped), and the
  /// first frames, exposed in that fast move, lose every point to the stereo check. The scanner's
  /// rescans of missed stretches set it: their first frames lie inside the gap (an empty column
  /// through a box splits its faces). The whole sweep does not yet: its first frames lie at the
  /// workspace's edge, and waiting there shifts the simulated cameras' noise draws of scenes
  /// that stand at the edges of the perception tests (issue 37).
  bool start_at_rest = false;
};

struct ScanResult {
  RangeImage range{0, 0};
  int points = 0;
  int rejected = 0;
  /// Stripe positions the sweep missed (frames the host never saw: it was held up, say by a
  /// serial dropout, and the cameras showed only their newest frame) and that were swept again,
  /// and the frames that pass added. A gap is a step between two frames' counts over
  /// kGapSteps sweep steps.
  int gaps_rescanned = 0;
  int frames_rescanned = 0;
  /// Gaps still there after the rescans (kMaxRescanPasses passes).
  int gaps_left = 0;
  cv::Mat ambient_left;  ///< the left image with the laser off: the colour source
  /// kOk, or the device status that ended the scan early (the range is then empty and the laser
  /// has been told to go off); `failed_device` names the device that said it ("laser",
  /// "cameras").
  device::Status status = device::Status::kOk;
  std::string failed_device;
};

/// Runs the laser from sweep.start_count to sweep.end_count at constant speed (laser already
/// on or off as the caller set it) and calls `on_frame` for every frame grabbed while it moves.
/// The frames of the fast move to the start are grabbed without images
/// (StereoCamera::GrabWithoutImages).
/// Returns the device status that ended it early, or kOk; `failed_device` (when given) is then
/// set to the device that said it ("laser" or "cameras").
device::Status Sweep(device::RobotDevices& dev, const SweepConfig& sweep,
                     const std::function<void(const device::StereoFrame&)>& on_frame,
                     std::string* failed_device = nullptr);

/// Checks that the intrinsics describe cameras of the frames' size.
/// @throws hgrasp::InputError naming the intrinsics file (cameras.path), the sizes of both.
void CheckFrameSize(const robot::StereoIntrinsics& cameras, const device::StereoFrame& frame);

/// A step between two neighbouring frames' encoder counts over this many sweep steps is a gap.
inline constexpr double kGapSteps = 2.5;
/// Passes of rescanning the gaps a sweep left.
inline constexpr int kMaxRescanPasses = 2;

class Scanner {
 public:
  Scanner(robot::HeadKinematics head, robot::StereoIntrinsics cameras,
          robot::LaserCalibration laser, StripeFrameConfig config = {});

  /// One ambient frame (laser off), then a sweep with the laser on; the head must hold still.
  /// Every device status is checked: the first that is not kOk ends the scan (ScanResult::status
  /// and failed_device), with the laser told to go off.
  ScanResult Scan(device::RobotDevices& dev, const SweepConfig& sweep);

  /// Processes one frame pair as Scan does, into column `col` of `range` (which must have as
  /// many rows as the images): for benchmarks and tests. `ambient` is the pair taken with the
  /// laser off: it is subtracted from the frame before the stripe is searched (see
  /// StripeFrameProcessor::SetAmbient), and its left image gives each point's colour.
  void ProcessFrame(const device::StereoFrame& frame, const device::StereoFrame& ambient,
                    RangeImage* range, int col, StripeFrameResult* result);

  /// Verge readings within this step (rad) share one rectification: 1e-5 rad moves a point
  /// 6 um at 0.6 m, far below the Biclops encoder's own step, and servo jitter never builds a
  /// new one.
  static constexpr double kVergeStepRad = 1e-5;
  static double VergeKey(double verge);

  /// The rectification at a verge angle (rad), computed once per angle.
  const Rectification& RectificationAt(double verge);
  /// The light plane's coefficients at an encoder count, for the cameras at a verge angle.
  LaserCoefficients CoefficientsAt(std::int32_t count, double verge);

  const robot::HeadKinematics& head() const { return head_; }
  const robot::StereoIntrinsics& cameras() const { return cameras_; }

 private:
  robot::HeadKinematics head_;
  robot::StereoIntrinsics cameras_;
  robot::LaserCalibration laser_;
  StripeFrameConfig config_;
  std::map<double, std::unique_ptr<Rectification>> rectifications_;
  std::map<double, std::unique_ptr<StripeFrameProcessor>> processors_;
};

/// The quality a laser calibration must reach to be written (hgrasp calibrate laser refuses a
/// result below it, exit 1 with the figures). Measured in the sim: over the calibration target
/// (two steps across the whole sweep, scenarios/calibration_target.yaml) at camera noise 0, 2
/// and 5, residue 0.088-0.115 px, points 0.100-0.138 mm, median plane angle 0.033-0.052 deg
/// (and the calibrated planes within 0.016 deg / 0.08 mm of the truth); over scenes that are no
/// target (the default's two boxes: most stripe positions on the table alone; a box before a
/// wall; the interference scene), median plane angles of 5.3-51 deg, which the model alone
/// would have written as a plane 45 deg from the truth.
struct LaserCalibrationQuality {
  double min_fitted_fraction = 0.6;   ///< frames whose stripe determined a plane, of all frames
  double min_span_fraction = 0.8;     ///< the counts used span this much of the sweep
  double max_rms_residue_px = 0.25;   ///< eq. 5 residue RMS over every pair, after the model fit
  double max_rms_point_mm = 0.5;      ///< stripe points' RMS distance from the model's planes
  double max_median_plane_deg = 0.2;  ///< per-count planes' median angle from the model's
};

struct LaserCalibrationReport {
  int frames = 0;               ///< frames in the sweep
  int counts_fitted = 0;        ///< frames whose stripe determined a plane (eq. 6)
  int counts_used = 0;          ///< of those, the planes consistent with their neighbours
  double span_fraction = 0;     ///< the counts used span this fraction of the sweep's counts
  double rms_residue_px = 0;    ///< eq. 5 residue over all pairs used, after the model fit
  double rms_point_mm = 0;      ///< stripe points' RMS distance from the model's planes (mm)
  double median_plane_deg = 0;  ///< per-count planes' median angle from the model's (deg)
  std::string failed_device;    ///< set when a device's status ended the calibration
  device::Status status = device::Status::kOk;  ///< that status
  std::string failure;  ///< empty when a calibration was made at the stated quality; else why

  /// The figures in one line, for logs and messages.
  std::string Figures() const;
};

/// Self-calibration: sweeps the laser over a non-planar target, fits eq. 6 per encoder count and
/// the rotating-plane model over all counts, and measures the result against `quality`. The
/// head must hold still. nullopt, with report->failure saying why, when a device's status ended
/// it (report->failed_device) or the result is below `quality`.
std::optional<robot::LaserCalibration> CalibrateLaser(
    device::RobotDevices& dev, const robot::HeadKinematics& head,
    const robot::StereoIntrinsics& cameras, const SweepConfig& sweep, StripeFrameConfig config,
    LaserCalibrationReport* report, const LaserCalibrationQuality& quality = {});

}  // namespace hgrasp::scan
