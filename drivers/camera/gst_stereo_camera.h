#pragma once
/// @file The real stereo cameras: two GStreamer pipelines named in the scenario's devices block
/// (v4l2src on the robot's frame grabber, or the twin's streams: tcpclientsrc ! gdpdepay), each
/// ending in an appsink the driver reads with a timeout, with the laser encoder count the laser
/// board latched at the exposure and the head joints read at grab time.
///
/// The appsink read is the element named `sink`, else the pipeline's last element when it is an
/// appsink, else the only appsink in the pipeline; Open fails otherwise.
///
/// What the driver does with each pipeline's appsink (whatever the pipeline string set):
/// - caps video/x-raw,format=BGR when the appsink has none (a pipeline that cannot give BGR
///   fails to negotiate: Grab reports GStreamer's error);
/// - sync=false: a frame is handed on when it arrives, never held until its PTS on the
///   pipeline's clock (the twin's PTS are on the twin's clock, not this pipeline's);
/// - max-buffers=kQueuedFrames (1), drop=true: a consumer that falls behind gets the newest
///   frame, never an older one (the board keeps only the last 16 latches, and TCP would
///   otherwise buffer seconds of stale frames); the frames dropped are not silent:
///   gaps in the buffer offsets (the frame numbers) are counted in stats().frames_lost.
///
/// Left and right are paired by frame number (camera/exposure_pairing.h, shared with the twin's
/// lockstep camera) when both carry one (GStreamer's buffer offset:
/// the twin's server sets the board's frame number; v4l2src and videotestsrc count frames from
/// the stream's start): the older is dropped until the numbers match, at most
/// kMaxPairingDrops frames; streams further apart do not count the same frames (kBadReply).
/// Without numbers (GST_BUFFER_OFFSET_NONE) the frames are paired as they arrive.

#include <cstdint>
#include <functional>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "camera/exposure_pairing.h"
#include "device/head.h"
#include "device/stereo_camera.h"

namespace hgrasp::drivers {

struct GstCameraConfig {
  std::string left, right;        ///< GStreamer pipelines ending in appsink
  int width = 320, height = 240;  ///< what each frame must be (DESIGN.md: PAL 320 x 240)
  /// The longest wait for a camera's next frame (s) before Grab reports kTimeout: a stream that
  /// stops is noticed within it (12 frame periods at 25 frames/s by default).
  double frame_timeout_s = 0.5;
  LatchPairing latch_pairing = LatchPairing::kLatest;
  /// With kOffset: the board's frame number minus the buffer's offset (0 for the twin, whose
  /// offsets are the board's frame numbers).
  int frame_offset = 0;
  /// Frames that may arrive after a command although they were exposed before it
  /// (StereoCamera::frames_in_flight): exposure to arrival takes up to this many frame periods.
  /// 3 (120 ms): the twin renders each frame after its exposure, up to 100 ms on a loaded
  /// 2-core machine with software rendering (with 0, and with 1 in a slowed-down run, the LED
  /// tracker saw flash frames from before the switch and lost the gripper); a frame grabber
  /// delivers a frame about one period after its exposure.
  int frames_in_flight = 3;
};

/// Counters since Open.
struct GstCameraStats {
  std::uint64_t pairs = 0;            ///< frame pairs Grab returned
  std::uint64_t frames_lost[2] = {};  ///< frames missing between offsets (left, right)
  /// Frames dropped because the other camera had none of the same number, or failed.
  std::uint64_t unpaired[2] = {};
};

class GstStereoCamera final : public device::StereoCamera {
 public:
  /// Frames each appsink holds: 1, the newest. A Grab after a command returns a frame at most
  /// one period older than the call, as a frame grabber's "latest frame" read does, so that the
  /// task's commands act on what the cameras see now (with 4 queued, a frame 160 ms old read
  /// after a head move showed the head before the move, and the scan's laser-off reference
  /// frame was of another view). A consumer slower than 25 frames/s loses frames, counted.
  static constexpr int kQueuedFrames = 1;
  /// The most frames Grab drops from one camera to find the other's frame number; streams
  /// further apart than this do not count the same frames and Grab reports kBadReply.
  static constexpr int kMaxPairingDrops = drivers::kMaxPairingDrops;

  /// Opens and starts both pipelines. `latch` may be empty (no board: the count stays 0 and
  /// laser_on false); `head` may be null (joints stay 0); both must outlive the camera. Returns
  /// nullptr and sets *error ("left camera: ..." or "right camera: ...", the pipeline and
  /// GStreamer's message) when a pipeline does not parse, has no appsink to read or does not
  /// start (a tcpclientsrc with no server listening).
  static std::unique_ptr<GstStereoCamera> Open(const GstCameraConfig& config, LatchSource latch,
                                               device::Head* head, std::string* error);
  ~GstStereoCamera() override;
  GstStereoCamera(const GstStereoCamera&) = delete;
  GstStereoCamera& operator=(const GstStereoCamera&) = delete;

  /// Waits for the next frame of both cameras, paired by frame number (the buffer offset) when
  /// both streams carry one. kTimeout when a camera sends nothing for frame_timeout_s;
  /// kDisconnected when a stream has ended or its pipeline failed (GStreamer's message in
  /// last_error()); kBadReply when a frame is not width x height BGR, when the streams' frame
  /// numbers cannot be paired, or when latch_pairing is offset and a frame has no number; the
  /// latch or head reading failing is reported with their status, the images kept.
  /// `frame->t_s` is the left frame's PTS (its exposure on the source's clock) when it has one,
  /// else the time since the first frame.
  device::Status Grab(device::StereoFrame* frame) override;

  /// GstCameraConfig::frames_in_flight.
  int frames_in_flight() const override { return config_.frames_in_flight; }

  const std::string& last_error() const { return last_error_; }
  const GstCameraStats& stats() const { return stats_; }

 private:
  struct Stream;  // one camera's pipeline (GStreamer types stay in the .cc)

  GstStereoCamera(GstCameraConfig config, LatchSource latch, device::Head* head);
  /// Pulls camera i's next sample into streams_[i].pending unless one is pending.
  device::Status Pull(int i);
  /// Drops camera i's pending sample.
  void Drop(int i);
  /// Pulls one frame of each camera, of the same exposure (pending in streams_).
  device::Status PullPair();
  /// Checks camera i's pending frame (raw BGR of the configured size) and copies it out.
  device::Status CopyImage(int i, cv::Mat* image);

  GstCameraConfig config_;
  LatchSource latch_;
  device::Head* head_;
  std::unique_ptr<Stream> streams_[2];
  std::uint64_t sequence_ = 0;
  std::string last_error_;
  double t0_ = -1.0;
  GstCameraStats stats_;
};

}  // namespace hgrasp::drivers
