#include "camera/gst_stereo_server.h"

#include <gst/app/gstappsrc.h>
#include <gst/video/video.h>

#include <atomic>
#include <cmath>
#include <cstring>

#include "camera/gst_util.h"
#include "common/error.h"

namespace hgrasp::drivers {

struct GstStereoServer::Stream {
  GstElement* pipeline = nullptr;
  GstElement* src = nullptr;   // the appsrc, owned by the pipeline
  GstElement* sink = nullptr;  // the tcpserversink, owned by the pipeline
  int port = 0;
  std::size_t frame_bytes = 0, stride = 0;
  std::uint64_t max_bytes = 0;
  std::atomic<bool> stopped{false};
  std::atomic<std::uint64_t> pushed{0}, refused{0}, withheld{0};

  ~Stream() {
    if (pipeline != nullptr) {
      gst_element_set_state(pipeline, GST_STATE_NULL);
      gst_object_unref(pipeline);
    }
  }
};

namespace {

const char* const kNames[2] = {"left", "right"};

void DemandCamera(int camera) {
  HGRASP_DEMAND_MSG(camera == 0 || camera == 1, "camera must be 0 (left) or 1 (right)");
}

}  // namespace

GstStereoServer::GstStereoServer(std::string host, int width, int height)
    : host_(std::move(host)), width_(width), height_(height) {}

GstStereoServer::~GstStereoServer() = default;

std::unique_ptr<GstStereoServer> GstStereoServer::Open(const std::string& host, int port_left,
                                                       int port_right, int width, int height,
                                                       std::string* error) {
  HGRASP_DEMAND_MSG(width > 0 && height > 0, "a stream's frames must have a size");
  gst::Init();
  std::unique_ptr<GstStereoServer> server(new GstStereoServer(host, width, height));
  const int ports[2] = {port_left, port_right};
  GstVideoInfo info;
  gst_video_info_set_format(&info, GST_VIDEO_FORMAT_BGR, static_cast<guint>(width),
                            static_cast<guint>(height));
  GST_VIDEO_INFO_FPS_N(&info) = 25;
  GST_VIDEO_INFO_FPS_D(&info) = 1;
  for (int i = 0; i < 2; ++i) {
    auto fail = [&](const std::string& what) {
      if (error != nullptr) *error = std::string(kNames[i]).append(" camera: ").append(what);
      return nullptr;
    };
    server->streams_[i] = std::make_unique<Stream>();
    Stream& s = *server->streams_[i];
    s.pipeline = gst_pipeline_new(nullptr);
    gst_object_ref_sink(s.pipeline);
    s.src = gst_element_factory_make("appsrc", nullptr);
    GstElement* pay = gst_element_factory_make("gdppay", nullptr);
    s.sink = gst_element_factory_make("tcpserversink", nullptr);
    if (s.src == nullptr || pay == nullptr || s.sink == nullptr) {
      for (GstElement* e : {s.src, pay, s.sink}) {
        if (e != nullptr) gst_object_unref(gst_object_ref_sink(e));
      }
      s.src = s.sink = nullptr;
      return fail(
          "GStreamer lacks appsrc, gdppay or tcpserversink (gstreamer1.0-plugins-base and "
          "-bad)");
    }
    gst_bin_add_many(GST_BIN(s.pipeline), s.src, pay, s.sink, nullptr);
    if (!gst_element_link_many(s.src, pay, s.sink, nullptr)) {
      return fail("GStreamer cannot link appsrc ! gdppay ! tcpserversink");
    }
    s.frame_bytes = GST_VIDEO_INFO_SIZE(&info);
    s.stride = static_cast<std::size_t>(GST_VIDEO_INFO_PLANE_STRIDE(&info, 0));
    s.max_bytes = static_cast<std::uint64_t>(kQueuedFrames) * s.frame_bytes;
    GstCaps* caps = gst_video_info_to_caps(&info);
    // Live, stamped by us (PTS = the exposure), never blocking Push.
    g_object_set(s.src, "caps", caps, "is-live", TRUE, "format", GST_FORMAT_TIME, "do-timestamp",
                 FALSE, "block", FALSE, "max-bytes", static_cast<guint64>(s.max_bytes),
                 "emit-signals", FALSE, nullptr);
    gst_caps_unref(caps);
    // Sent as soon as rendered (the PTS are on the twin's clock, not this pipeline's); a client
    // that falls behind skips to the newest frame; new clients start at the newest.
    g_object_set(s.sink, "host", host.c_str(), "port", ports[i], "sync", FALSE, "async", FALSE,
                 "recover-policy", 1 /* latest */, "sync-method", 0 /* latest */, "unit-format",
                 GST_FORMAT_BUFFERS, "units-soft-max", static_cast<gint64>(kClientSoftMax),
                 nullptr);
    // A port already taken is an ERROR on the bus, not always a failed state change.
    const bool started =
        gst_element_set_state(s.pipeline, GST_STATE_PLAYING) != GST_STATE_CHANGE_FAILURE;
    if (const std::string text = gst::DrainBus(s.pipeline); !started || !text.empty()) {
      std::string what = "GStreamer cannot serve on ";
      what.append(host).append(":").append(std::to_string(ports[i])).append(" (");
      return fail(what.append(text.empty() ? "no message" : text).append(")"));
    }
    gint port = 0;
    g_object_get(s.sink, "current-port", &port, nullptr);
    if (port <= 0) return fail("tcpserversink reports no port it listens on");
    s.port = port;
  }
  return server;
}

int GstStereoServer::port(int camera) const {
  DemandCamera(camera);
  return streams_[camera]->port;
}

std::string GstStereoServer::ClientPipeline(int camera) const {
  DemandCamera(camera);
  const bool any = host_.empty() || host_ == "0.0.0.0" || host_ == "::";
  std::string p = "tcpclientsrc host=";
  p.append(any ? "127.0.0.1" : host_).append(" port=").append(std::to_string(port(camera)));
  return p.append(" ! gdpdepay ! appsink");
}

bool GstStereoServer::Push(int camera, const cv::Mat& bgr, std::uint64_t frame_number,
                           double exposure_s) {
  DemandCamera(camera);
  HGRASP_DEMAND_MSG(bgr.cols == width_ && bgr.rows == height_ && bgr.type() == CV_8UC3,
                    "a frame pushed must be the stream's size, BGR");
  HGRASP_DEMAND_MSG(std::isfinite(exposure_s) && exposure_s >= 0.0,
                    "a frame's exposure time must be finite and >= 0");
  Stream& s = *streams_[camera];
  if (s.stopped) {
    ++s.withheld;
    return false;
  }
  // Our own bound: appsrc with block=false would queue past max-bytes.
  GstAppSrc* src = GST_APP_SRC(s.src);
  if (gst_app_src_get_current_level_bytes(src) + s.frame_bytes > s.max_bytes) {
    ++s.refused;
    return false;
  }
  GstBuffer* buffer = gst_buffer_new_allocate(nullptr, s.frame_bytes, nullptr);
  GstMapInfo map;
  if (buffer == nullptr || !gst_buffer_map(buffer, &map, GST_MAP_WRITE)) {
    if (buffer != nullptr) gst_buffer_unref(buffer);
    ++s.refused;
    return false;
  }
  const std::size_t row = static_cast<std::size_t>(width_) * 3;
  for (int y = 0; y < height_; ++y) {
    std::uint8_t* line = map.data + static_cast<std::size_t>(y) * s.stride;
    std::memcpy(line, bgr.ptr(y), row);
    std::memset(line + row, 0, s.stride - row);  // rows padded to 4 bytes (GStreamer's layout)
  }
  gst_buffer_unmap(buffer, &map);
  GST_BUFFER_OFFSET(buffer) = frame_number;
  GST_BUFFER_OFFSET_END(buffer) = frame_number + 1;
  GST_BUFFER_PTS(buffer) = static_cast<GstClockTime>(std::llround(exposure_s * 1e9));
  GST_BUFFER_DURATION(buffer) = static_cast<GstClockTime>(std::llround(kFramePeriodS * 1e9));
  // Takes the buffer; not OK only when the stream is flushing or at its end.
  if (gst_app_src_push_buffer(src, buffer) != GST_FLOW_OK) {
    ++s.refused;
    return false;
  }
  ++s.pushed;
  return true;
}

void GstStereoServer::Stop(int camera) {
  DemandCamera(camera);
  streams_[camera]->stopped = true;
}

void GstStereoServer::Resume(int camera) {
  DemandCamera(camera);
  streams_[camera]->stopped = false;
}

bool GstStereoServer::stopped(int camera) const {
  DemandCamera(camera);
  return streams_[camera]->stopped;
}

GstStreamStats GstStereoServer::stats(int camera) const {
  DemandCamera(camera);
  const Stream& s = *streams_[camera];
  return {s.pushed.load(), s.refused.load(), s.withheld.load()};
}

int GstStereoServer::clients(int camera) const {
  DemandCamera(camera);
  guint n = 0;
  g_object_get(streams_[camera]->sink, "num-handles", &n, nullptr);
  return static_cast<int>(n);
}

int GstStereoServer::queued(int camera) const {
  DemandCamera(camera);
  guint n = 0;
  g_object_get(streams_[camera]->sink, "buffers-queued", &n, nullptr);
  return static_cast<int>(n);
}

}  // namespace hgrasp::drivers
