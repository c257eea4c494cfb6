#include "camera/gst_stereo_camera.h"

#include <gst/app/gstappsink.h>
#include <gst/video/video.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>

#include "camera/gst_util.h"

namespace hgrasp::drivers {

using device::Status;

struct GstStereoCamera::Stream {
  GstElement* pipeline = nullptr;
  GstElement* sink = nullptr;    // the appsink (a reference of our own)
  GstSample* pending = nullptr;  // pulled, not yet returned (waits for the other camera)
  std::optional<std::uint64_t> last_offset;  // of the last frame pulled
  std::string failure;                       // once the pipeline has failed or ended: why (sticky)

  ~Stream() {
    if (pending != nullptr) gst_sample_unref(pending);
    if (pipeline != nullptr) {
      gst_element_set_state(pipeline, GST_STATE_NULL);
      gst_object_unref(pipeline);
    }
    if (sink != nullptr) gst_object_unref(sink);
  }
};

namespace {

const char* const kNames[2] = {"left", "right"};

std::string Camera(int i) { return std::string(kNames[i]) + " camera: "; }

std::string Seconds(double s) {
  std::ostringstream o;
  o << s;
  return o.str();
}

std::optional<std::uint64_t> OffsetOf(GstSample* sample) {
  GstBuffer* b = gst_sample_get_buffer(sample);
  if (b == nullptr || GST_BUFFER_OFFSET(b) == GST_BUFFER_OFFSET_NONE) return std::nullopt;
  return GST_BUFFER_OFFSET(b);
}

// The appsink to read: the element named "sink", else the pipeline's last element, else the
// only appsink in it. nullptr and *why otherwise. Returns a new reference.
GstElement* FindAppSink(GstElement* pipeline, std::string* why) {
  if (!GST_IS_BIN(pipeline)) {
    if (GST_IS_APP_SINK(pipeline)) return GST_ELEMENT(gst_object_ref(pipeline));
    *why = "it is a single element, not a pipeline ending in appsink";
    return nullptr;
  }
  GstBin* bin = GST_BIN(pipeline);
  if (GstElement* named = gst_bin_get_by_name(bin, "sink")) {
    if (GST_IS_APP_SINK(named)) return named;
    *why = std::string("its element named sink is a ") + G_OBJECT_TYPE_NAME(named) +
           ", not an appsink";
    gst_object_unref(named);
    return nullptr;
  }
  // gst_parse_launch adds the elements in the order written; a bin keeps its newest child first.
  GST_OBJECT_LOCK(bin);
  GstElement* last = bin->children != nullptr ? GST_ELEMENT(bin->children->data) : nullptr;
  if (last != nullptr && GST_IS_APP_SINK(last)) {
    gst_object_ref(last);
    GST_OBJECT_UNLOCK(bin);
    return last;
  }
  GST_OBJECT_UNLOCK(bin);
  GstIterator* it = gst_bin_iterate_recurse(bin);
  GValue item = G_VALUE_INIT;
  GstElement* found = nullptr;
  int count = 0;
  while (gst_iterator_next(it, &item) == GST_ITERATOR_OK) {
    GObject* element = G_OBJECT(g_value_get_object(&item));
    if (GST_IS_APP_SINK(element)) {
      ++count;
      if (found == nullptr) found = GST_ELEMENT(gst_object_ref(element));
    }
    g_value_reset(&item);
  }
  g_value_unset(&item);
  gst_iterator_free(it);
  if (count == 1) return found;
  if (found != nullptr) gst_object_unref(found);
  *why = count == 0 ? std::string("it has no appsink to read frames from")
                    : std::to_string(count) +
                          " appsinks and none named sink: name the one to read (appsink name=sink)";
  return nullptr;
}

}  // namespace

GstStereoCamera::GstStereoCamera(GstCameraConfig config, LatchSource latch, device::Head* head)
    : config_(std::move(config)), latch_(std::move(latch)), head_(head) {}

GstStereoCamera::~GstStereoCamera() = default;

std::unique_ptr<GstStereoCamera> GstStereoCamera::Open(const GstCameraConfig& config,
                                                       LatchSource latch, device::Head* head,
                                                       std::string* error) {
  gst::Init();
  std::unique_ptr<GstStereoCamera> camera(new GstStereoCamera(config, std::move(latch), head));
  const std::string* pipelines[2] = {&config.left, &config.right};
  auto fail = [&](int i, const std::string& what) {
    if (error != nullptr) {
      *error = Camera(i);
      error->append(what).append(" '").append(*pipelines[i]).append("'");
    }
    return nullptr;
  };
  for (int i = 0; i < 2; ++i) {
    camera->streams_[i] = std::make_unique<Stream>();
    Stream& s = *camera->streams_[i];
    GError* parse_error = nullptr;
    s.pipeline = gst_parse_launch(pipelines[i]->c_str(), &parse_error);
    if (s.pipeline != nullptr) gst_object_ref_sink(s.pipeline);
    if (parse_error != nullptr) {
      std::string text =
          std::string("GStreamer cannot parse the pipeline (") + parse_error->message + ")";
      g_error_free(parse_error);
      return fail(i, text);
    }
    if (s.pipeline == nullptr) return fail(i, "GStreamer cannot parse the pipeline");
    std::string why;
    s.sink = FindAppSink(s.pipeline, &why);
    if (s.sink == nullptr) return fail(i, "the pipeline must end in an appsink (" + why + "):");
    // The appsink's policy (gst_stereo_camera.h): BGR unless the pipeline asks otherwise, no
    // clock sync, a few of the newest frames queued.
    GstAppSink* sink = GST_APP_SINK(s.sink);
    if (GstCaps* caps = gst_app_sink_get_caps(sink)) {
      gst_caps_unref(caps);
    } else {
      GstCaps* bgr = gst_caps_from_string("video/x-raw,format=BGR");
      gst_app_sink_set_caps(sink, bgr);
      gst_caps_unref(bgr);
    }
    g_object_set(s.sink, "sync", FALSE, "emit-signals", FALSE, "max-buffers",
                 static_cast<guint>(kQueuedFrames), "drop", TRUE, nullptr);
    const bool started =
        gst_element_set_state(s.pipeline, GST_STATE_PLAYING) != GST_STATE_CHANGE_FAILURE;
    if (const std::string text = gst::DrainBus(s.pipeline); !started || !text.empty()) {
      return fail(i, "GStreamer cannot start the pipeline (" +
                         (text.empty() ? std::string("no message") : text) + ")");
    }
  }
  return camera;
}

Status GstStereoCamera::Pull(int i) {
  Stream& s = *streams_[i];
  if (s.pending != nullptr) return Status::kOk;
  if (s.failure.empty()) s.failure = gst::DrainBus(s.pipeline);
  if (s.failure.empty()) {
    const auto timeout = static_cast<GstClockTime>(std::llround(config_.frame_timeout_s * 1e9));
    s.pending = gst_app_sink_try_pull_sample(GST_APP_SINK(s.sink), timeout);
    if (s.pending == nullptr) {
      // Silence, the end of the stream (the frames before it were all handed on), or a failure
      // upstream (an ERROR on the bus: the appsink never hears of it).
      s.failure = gst::DrainBus(s.pipeline);
      if (s.failure.empty() && gst_app_sink_is_eos(GST_APP_SINK(s.sink))) {
        s.failure = "end of stream";
      }
      if (s.failure.empty()) {
        last_error_ =
            Camera(i) + "no frame for " + Seconds(config_.frame_timeout_s) + " s (frame_timeout_s)";
        return Status::kTimeout;
      }
    }
  }
  if (!s.failure.empty()) {
    last_error_ = Camera(i) + (s.failure == "end of stream" ? std::string("the stream has ended")
                                                            : "the pipeline failed: " + s.failure);
    return Status::kDisconnected;
  }
  // Gaps in the frame numbers are frames lost (dropped by the appsink or before it).
  if (const std::optional<std::uint64_t> offset = OffsetOf(s.pending)) {
    if (s.last_offset && *offset > *s.last_offset + 1) {
      stats_.frames_lost[i] += *offset - *s.last_offset - 1;
    }
    s.last_offset = offset;
  }
  return Status::kOk;
}

void GstStereoCamera::Drop(int i) {
  Stream& s = *streams_[i];
  if (s.pending != nullptr) gst_sample_unref(s.pending);
  s.pending = nullptr;
}

Status GstStereoCamera::PullPair() {
  // One frame of each camera, of the same exposure: when both carry frame numbers (buffer
  // offsets), the older is dropped until they match.
  for (int drops = 0;; ++drops) {
    for (int i = 0; i < 2; ++i) {
      const Status s = Pull(i);
      if (s != Status::kOk) {
        // The other camera's frame would be stale by the time this one comes back.
        if (streams_[1 - i]->pending != nullptr) ++stats_.unpaired[1 - i];
        Drop(1 - i);
        return s;
      }
    }
    const std::optional<std::uint64_t> a = OffsetOf(streams_[0]->pending);
    const std::optional<std::uint64_t> b = OffsetOf(streams_[1]->pending);
    const PairStep step = NextPairStep(a, b, drops, kMaxPairingDrops);
    if (step == PairStep::kPaired) return Status::kOk;
    const int older = step == PairStep::kDropLeft    ? 0
                      : step == PairStep::kDropRight ? 1
                                                     : OlderOf(*a, *b);
    Drop(older);
    ++stats_.unpaired[older];
    if (step == PairStep::kUnpairable) {
      last_error_ = UnpairableMessage(*a, *b, kMaxPairingDrops);
      return Status::kBadReply;
    }
  }
}

Status GstStereoCamera::CopyImage(int i, cv::Mat* image) {
  GstSample* sample = streams_[i]->pending;
  GstVideoInfo info;
  GstCaps* caps = gst_sample_get_caps(sample);
  GstBuffer* buffer = gst_sample_get_buffer(sample);
  if (caps == nullptr || buffer == nullptr || !gst_video_info_from_caps(&info, caps)) {
    gchar* text = caps != nullptr ? gst_caps_to_string(caps) : nullptr;
    last_error_ = Camera(i) + "got a frame with caps '" +
                  (text != nullptr ? std::string(text) : std::string("none")) +
                  "'; expected raw video";
    g_free(text);
    return Status::kBadReply;
  }
  const GstVideoFormat format = GST_VIDEO_INFO_FORMAT(&info);
  if (info.width != config_.width || info.height != config_.height ||
      format != GST_VIDEO_FORMAT_BGR) {
    last_error_ = Camera(i) + "got a " + std::to_string(info.width) + " x " +
                  std::to_string(info.height) + " " + gst_video_format_to_string(format) +
                  " frame; expected " + std::to_string(config_.width) + " x " +
                  std::to_string(config_.height) + " BGR";
    return Status::kBadReply;
  }
  GstVideoFrame video;
  if (!gst_video_frame_map(&video, &info, buffer, GST_MAP_READ)) {
    last_error_ = Camera(i) + "a frame's buffer cannot be read (" +
                  std::to_string(gst_buffer_get_size(buffer)) + " bytes for " +
                  std::to_string(info.width) + " x " + std::to_string(info.height) + " BGR)";
    return Status::kBadReply;
  }
  // A new buffer for every frame: callers keep frames (the scanner keeps every frame of a
  // sweep), and cv::Mat copies share data; create() would reuse the last frame's buffer.
  *image = cv::Mat(config_.height, config_.width, CV_8UC3);
  const auto* data = static_cast<const std::uint8_t*>(GST_VIDEO_FRAME_PLANE_DATA(&video, 0));
  const int stride = GST_VIDEO_FRAME_PLANE_STRIDE(&video, 0);
  const std::size_t row = static_cast<std::size_t>(config_.width) * 3;
  for (int y = 0; y < config_.height; ++y) {
    std::memcpy(image->ptr(y), data + static_cast<std::ptrdiff_t>(y) * stride, row);
  }
  gst_video_frame_unmap(&video);
  return Status::kOk;
}

Status GstStereoCamera::Grab(device::StereoFrame* frame) {
  // 1. One frame of each camera, of the same exposure.
  if (const Status s = PullPair(); s != Status::kOk) return s;

  // 2. The images, checked and copied out of the samples.
  const double now =
      std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  if (t0_ < 0.0) t0_ = now;
  for (int i = 0; i < 2; ++i) {
    const Status s = CopyImage(i, i == 0 ? &frame->left : &frame->right);
    if (s != Status::kOk) {
      Drop(0);
      Drop(1);
      return s;
    }
  }
  GstBuffer* left = gst_sample_get_buffer(streams_[0]->pending);
  const std::optional<std::uint64_t> offset = OffsetOf(streams_[0]->pending);
  frame->t_s = GST_BUFFER_PTS_IS_VALID(left)
                   ? static_cast<double>(GST_BUFFER_PTS(left)) / static_cast<double>(GST_SECOND)
                   : now - t0_;
  Drop(0);
  Drop(1);
  frame->sequence = sequence_++;
  ++stats_.pairs;

  // 3. What the board latched at this exposure, and the head.
  return AnnotateExposure(config_.latch_pairing, config_.frame_offset, offset, latch_, head_, frame,
                          &last_error_);
}

}  // namespace hgrasp::drivers
