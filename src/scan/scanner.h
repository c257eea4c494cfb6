#pragma once
/// @file The laser scanner: sweeps the stripe across the scene through the device seam and
/// turns the frames into a RangeImage with registered colour; and the laser's self-calibration.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core/mat.hpp>

#include "device/robot_devices.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/range_image.h"
#include "scan/stripe_frame.h"

namespace hgrasp::scan {

/// The sweep: from start to end count in `positions` frames (one stripe position per frame).
/// Left to right as the cameras see it, so that the range image's columns read like the images.
struct SweepConfig {
  std::int32_t start_count = 2400;  ///< +24 deg: the workspace's left edge and beyond
  std::int32_t end_count = -2400;   ///< -24 deg: its right edge
  int positions = 300;              ///< 12 s at 25 frames/s
};

struct ScanResult {
  RangeImage range{0, 0};
  int points = 0;
  int rejected = 0;
  cv::Mat ambient_left;  ///< the left image with the laser off: the colour source
};

/// Runs the laser from sweep.start_count to sweep.end_count at constant speed (laser already
/// on or off as the caller set it) and calls `on_frame` for every frame grabbed while it moves.
/// Returns the device status that ended it early, or kOk.
device::Status Sweep(device::RobotDevices& dev, const SweepConfig& sweep,
                     const std::function<void(const device::StereoFrame&)>& on_frame);

class Scanner {
 public:
  Scanner(robot::HeadKinematics head, robot::StereoIntrinsics cameras,
          robot::LaserCalibration laser, StripeFrameConfig config = {});

  /// One ambient frame (laser off), then a sweep with the laser on; the head must hold still.
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

struct LaserCalibrationReport {
  int frames = 0;             ///< frames in the sweep
  int counts_used = 0;        ///< frames whose stripe determined a plane
  double rms_residue_px = 0;  ///< eq. 5 residue over all pairs used, after the model fit
};

/// Self-calibration: sweeps the laser over a non-planar target, fits eq. 6 per encoder count and
/// the rotating-plane model over all counts. The head must hold still.
robot::LaserCalibration CalibrateLaser(device::RobotDevices& dev, const robot::HeadKinematics& head,
                                       const robot::StereoIntrinsics& cameras,
                                       const SweepConfig& sweep, StripeFrameConfig config,
                                       LaserCalibrationReport* report);

}  // namespace hgrasp::scan
