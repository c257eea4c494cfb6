#pragma once
/// @file The real stereo cameras: two OpenCV VideoCapture streams on GStreamer pipelines named in
/// the scenario's devices block (v4l2src on the robot's frame grabber), with the laser encoder
/// count the laser board latched at the exposure and the head joints read at grab time.

#include <cstdint>
#include <functional>
#include <memory>
#include <opencv2/videoio.hpp>
#include <string>

#include "device/head.h"
#include "device/stereo_camera.h"

namespace hgrasp::drivers {

/// What the laser board latched at the most recent camera frame (its vertical sync).
struct ExposureLatch {
  std::uint32_t frame = 0;         ///< the board's frame counter
  std::int32_t encoder_count = 0;  ///< laser motor encoder at that frame
  bool laser_on = false;
};
/// Asks the laser board for its latest latch.
using LatchSource = std::function<device::Status(ExposureLatch*)>;

struct GstCameraConfig {
  std::string left, right;        ///< GStreamer pipelines ending in appsink
  int width = 320, height = 240;  ///< what each frame must be (DESIGN.md: PAL 320 x 240)
};

class GstStereoCamera final : public device::StereoCamera {
 public:
  /// Opens both pipelines. `latch` may be empty (no board: the count stays 0 and laser_on
  /// false); `head` may be null (joints stay 0); both must outlive the camera. Returns nullptr
  /// and sets *error (which camera, the pipeline) when a pipeline cannot be opened.
  static std::unique_ptr<GstStereoCamera> Open(const GstCameraConfig& config, LatchSource latch,
                                               device::Head* head, std::string* error);

  /// Waits for the next frame of both cameras. kDisconnected when a stream has ended or failed;
  /// kBadReply when a frame is not width x height BGR (last_error() says what came); the latch
  /// or head reading failing is reported with their status, the images kept.
  device::Status Grab(device::StereoFrame* frame) override;

  const std::string& last_error() const { return last_error_; }

 private:
  GstStereoCamera(GstCameraConfig config, LatchSource latch, device::Head* head)
      : config_(std::move(config)), latch_(std::move(latch)), head_(head) {}

  GstCameraConfig config_;
  LatchSource latch_;
  device::Head* head_;
  cv::VideoCapture capture_[2];
  std::uint64_t sequence_ = 0;
  std::string last_error_;
  double t0_ = -1.0;
};

}  // namespace hgrasp::drivers
