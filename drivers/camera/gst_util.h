#pragma once
/// @file What the camera driver and the camera server share of GStreamer (internal to
/// hgrasp_camera: nothing outside drivers/camera includes it).

#include <gst/gst.h>

#include <mutex>
#include <string>

namespace hgrasp::drivers::gst {

/// gst_init, once per process, from any thread.
inline void Init() {
  static std::once_flag once;
  std::call_once(once, [] { gst_init(nullptr, nullptr); });
}

/// GStreamer's text of an ERROR or WARNING message: the message, then its debug detail (the
/// element and the reason, e.g. "streaming stopped, reason not-negotiated") on one line.
inline std::string MessageText(GstMessage* m) {
  GError* err = nullptr;
  gchar* debug = nullptr;
  if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
    gst_message_parse_error(m, &err, &debug);
  } else if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_WARNING) {
    gst_message_parse_warning(m, &err, &debug);
  } else {
    return GST_MESSAGE_TYPE_NAME(m);
  }
  std::string text = err != nullptr ? err->message : "unknown error";
  if (debug != nullptr) {
    std::string d(debug);
    for (char& c : d) {
      if (c == '\n') c = ' ';
    }
    text.append(" (").append(d).append(")");
  }
  if (err != nullptr) g_error_free(err);
  g_free(debug);
  return text;
}

/// Empties `element`'s bus (a pipeline posts state changes, latency, QoS... that nobody else
/// reads: left there they would pile up). Returns the text of the first ERROR among them; ""
/// when there was none (an EOS is left to the sink: frames may still be queued before it).
inline std::string DrainBus(GstElement* element) {
  GstBus* bus = gst_element_get_bus(element);
  if (bus == nullptr) return "";
  std::string failure;
  while (GstMessage* m = gst_bus_pop(bus)) {
    if (failure.empty() && GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) failure = MessageText(m);
    gst_message_unref(m);
  }
  gst_object_unref(bus);
  return failure;
}

}  // namespace hgrasp::drivers::gst
