#pragma once
/// @file The stereo camera pair behind the frame grabber.

#include <cstdint>
#include <opencv2/core/mat.hpp>

#include "device/head.h"
#include "device/status.h"

namespace hgrasp::device {

/// One exposure of both cameras, with what the robot's encoders read at that moment.
struct StereoFrame {
  double t_s = 0.0;                      ///< exposure time (s)
  std::uint64_t sequence = 0;            ///< frame number since start
  cv::Mat left;                          ///< (240 x 320) CV_8UC3, BGR
  cv::Mat right;                         ///< (240 x 320) CV_8UC3, BGR
  std::int32_t laser_encoder_count = 0;  ///< laser encoder latched at exposure
  bool laser_on = false;
  HeadJoints head;  ///< head joints latched at exposure (rad)
};

class StereoCamera {
 public:
  virtual ~StereoCamera() = default;
  /// Blocks until the next frame pair (one every 40 ms at PAL rate) and fills `frame`.
  virtual Status Grab(StereoFrame* frame) = 0;
  /// Grab for a caller that will not look at the frame's images (it only waits for a motion to
  /// end): a camera that saves work by not making them leaves `left` and `right` empty (the
  /// simulator does not render them); by default it is Grab.
  virtual Status GrabWithoutImages(StereoFrame* frame) { return Grab(frame); }
  /// Frames a Grab just after a command may return that were exposed before the command took
  /// effect (the camera's latency, in frames): 0 for the lockstep simulation, where each Grab
  /// exposes a new frame after every command before it.
  virtual int frames_in_flight() const { return 0; }
};

}  // namespace hgrasp::device
