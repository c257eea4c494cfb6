#pragma once
/// @file The cameras' side of the wire for the twin: two live BGR streams (left, right), each
/// `appsrc ! gdppay ! tcpserversink`, that GstStereoCamera reads unchanged through
/// `tcpclientsrc ! gdpdepay ! appsink` (ClientPipeline). GDP carries each frame's caps, PTS and
/// buffer offset: the offset is the laser board's frame number (its VSYNC count) of the exposure,
/// the PTS the exposure time on the twin's clock.
///
/// Frames never pile up: the appsrc queues at most kQueuedFrames (a Push beyond that is refused
/// and counted); tcpserversink sends as soon as it can (no clock sync), keeps nothing for a
/// stream nobody reads, and resyncs a client that falls kClientSoftMax frames behind to the
/// newest frame (the driver counts the gap from the offsets). A client that connects late gets
/// the stream's header first (gdppay's streamheader: caps), then the frames from the next one on.

#include <cstdint>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>

namespace hgrasp::drivers {

/// Counters of one stream since Open.
struct GstStreamStats {
  std::uint64_t pushed = 0;    ///< frames handed to the stream
  std::uint64_t refused = 0;   ///< frames the appsrc did not take (its queue full, or flushing)
  std::uint64_t withheld = 0;  ///< frames not sent because the stream was stopped (Stop)
};

class GstStereoServer {
 public:
  /// Frames the appsrc holds before Push refuses (160 ms at 25 frames/s).
  static constexpr int kQueuedFrames = 4;
  /// Frames a client may fall behind before it is resynced to the newest (1 s).
  static constexpr int kClientSoftMax = 25;
  /// Each buffer's duration: PAL, 25 frames/s.
  static constexpr double kFramePeriodS = 0.04;

  /// Listens on `host` (e.g. 127.0.0.1; 0.0.0.0 for every interface) at `port_left` and
  /// `port_right` (0: a free port, see port()) and serves width x height BGR frames. nullptr and
  /// *error ("left camera: ...", GStreamer's message) when a stream cannot start (the port is
  /// taken).
  static std::unique_ptr<GstStereoServer> Open(const std::string& host, int port_left,
                                               int port_right, int width, int height,
                                               std::string* error);
  ~GstStereoServer();
  GstStereoServer(const GstStereoServer&) = delete;
  GstStereoServer& operator=(const GstStereoServer&) = delete;

  /// The port camera `camera` (0 left, 1 right) listens on.
  int port(int camera) const;
  /// The pipeline GstStereoCamera reads camera `camera` with:
  /// "tcpclientsrc host=H port=P ! gdpdepay ! appsink" (H 127.0.0.1 when listening on every
  /// interface).
  std::string ClientPipeline(int camera) const;

  /// Sends one exposure of camera `camera`: `bgr` (height x width) CV_8UC3, copied; its buffer
  /// offset `frame_number` (the board's frame counter at the exposure), its PTS `exposure_s`
  /// (>= 0, the twin's clock), its duration one frame period. Never blocks. false when the frame
  /// was refused (the stream's queue full: nobody drains it) or withheld (the stream stopped).
  /// Precondition: `bgr` is width x height CV_8UC3 (aborts otherwise). Safe to call for both
  /// cameras from different threads; one thread per camera.
  bool Push(int camera, const cv::Mat& bgr, std::uint64_t frame_number, double exposure_s);

  /// Stops camera `camera` sending frames (Push withholds them) while its clients stay
  /// connected: a camera stream that stops. Resume undoes it.
  void Stop(int camera);
  void Resume(int camera);
  bool stopped(int camera) const;

  GstStreamStats stats(int camera) const;
  /// Clients connected to camera `camera` now.
  int clients(int camera) const;
  /// Buffers tcpserversink holds for camera `camera`'s clients now.
  int queued(int camera) const;

 private:
  struct Stream;  // GStreamer types stay in the .cc

  GstStereoServer(std::string host, int width, int height);

  std::string host_;
  int width_, height_;
  std::unique_ptr<Stream> streams_[2];
};

}  // namespace hgrasp::drivers
