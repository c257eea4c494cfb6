#pragma once
/// @file The twin's cameras in lockstep: the exposures the twin renders in simulated time
/// (Twin with TwinOptions::lockstep) handed to the task as a device::StereoCamera, paired and
/// given the board's latch and the head by the code the GStreamer camera uses
/// (camera/exposure_pairing.h), so only the transport differs. Like the GStreamer camera's
/// appsink (one buffer, drop) it keeps each camera's newest frame: a frame not grabbed before
/// the next exposure is lost, and counted.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "camera/exposure_pairing.h"
#include "common/clock.h"
#include "device/stereo_camera.h"
#include "sim/twin/twin.h"

namespace hgrasp::sim {

/// Each camera's newest frame, as the twin hands them over (its FrameSink). Shared by the
/// twin's sink and the camera, so that either may be built first.
class LockstepFrames {
 public:
  struct Frame {
    std::uint64_t number = 0;  ///< the board's frame number
    double t_s = 0.0;          ///< exposure, twin time
    cv::Mat bgr;
  };
  /// The sink to give the twin.
  static FrameSink SinkFor(const std::shared_ptr<LockstepFrames>& frames);
  void Put(int camera, const cv::Mat& bgr, std::uint64_t number, double t_s);
  std::optional<Frame>& pending(int camera) { return pending_[camera]; }
  std::uint64_t lost(int camera) const { return lost_[camera]; }

 private:
  std::array<std::optional<Frame>, 2> pending_;
  std::array<std::uint64_t, 2> lost_{};
};

class LockstepCamera final : public device::StereoCamera {
 public:
  /// `latch` (the laser board's driver) may be empty and `head` null, as for GstStereoCamera;
  /// both must outlive the camera. Frames are paired by their numbers and the latch asked for
  /// by the same (latch_pairing offset, frame_offset 0: the twin's frame numbers are the
  /// board's).
  /// `develop` renders the newest exposure not yet rendered into `frames` (Twin::Develop),
  /// false when there is none: the camera calls it when it takes a frame, so that only the
  /// exposures taken are rendered.
  LockstepCamera(SimClock& clock, std::shared_ptr<LockstepFrames> frames,
                 std::function<bool()> develop, drivers::LatchSource latch, device::Head* head,
                 double frame_timeout_s = 0.5);

  /// The newest exposure of both cameras not yet grabbed, else the next one; kTimeout when none
  /// comes within frame_timeout_s (the twin's cameras stopped), kBadReply when the two
  /// cameras' frames cannot be paired; the latch's or the head's failure with their status.
  device::Status Grab(device::StereoFrame* frame) override;
  /// A pair grabbed just after a command may have been exposed before it: the newest frame
  /// waits for its Grab (one).
  int frames_in_flight() const override { return 1; }

  const std::string& last_error() const { return last_error_; }
  std::uint64_t pairs() const { return pairs_; }
  std::uint64_t unpaired(int camera) const { return unpaired_[camera]; }

 private:
  SimClock& clock_;
  std::shared_ptr<LockstepFrames> frames_;
  std::function<bool()> develop_;
  drivers::LatchSource latch_;
  device::Head* head_;
  double frame_timeout_s_;
  std::uint64_t sequence_ = 0, pairs_ = 0;
  std::array<std::uint64_t, 2> unpaired_{};
  std::string last_error_;
};

}  // namespace hgrasp::sim
