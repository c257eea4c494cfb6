#include "camera/gst_stereo_camera.h"

#include <chrono>

namespace hgrasp::drivers {

using device::Status;

std::unique_ptr<GstStereoCamera> GstStereoCamera::Open(const GstCameraConfig& config,
                                                       LatchSource latch, device::Head* head,
                                                       std::string* error) {
  std::unique_ptr<GstStereoCamera> camera(new GstStereoCamera(config, std::move(latch), head));
  const std::string* pipelines[2] = {&config.left, &config.right};
  const char* names[2] = {"left", "right"};
  for (int i = 0; i < 2; ++i) {
    if (!camera->capture_[i].open(*pipelines[i], cv::CAP_GSTREAMER) ||
        !camera->capture_[i].isOpened()) {
      if (error != nullptr) {
        *error = std::string(names[i]) + " camera: GStreamer cannot open the pipeline '" +
                 *pipelines[i] + "'";
      }
      return nullptr;
    }
  }
  return camera;
}

Status GstStereoCamera::Grab(device::StereoFrame* frame) {
  // grab() both first, then retrieve: the two exposures are as close together as the streams
  // allow (genlocked cameras on the robot deliver them together).
  for (int i = 0; i < 2; ++i) {
    if (!capture_[i].grab()) {
      last_error_ = std::string(i == 0 ? "left" : "right") + " camera: the stream has ended";
      return Status::kDisconnected;
    }
  }
  const double now =
      std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  if (t0_ < 0.0) t0_ = now;
  cv::Mat* images[2] = {&frame->left, &frame->right};
  for (int i = 0; i < 2; ++i) {
    if (!capture_[i].retrieve(*images[i])) {
      last_error_ = std::string(i == 0 ? "left" : "right") + " camera: no frame to retrieve";
      return Status::kDisconnected;
    }
    const cv::Mat& m = *images[i];
    if (m.cols != config_.width || m.rows != config_.height || m.type() != CV_8UC3) {
      last_error_ = std::string(i == 0 ? "left" : "right") + " camera: got a " +
                    std::to_string(m.cols) + " x " + std::to_string(m.rows) + " frame with " +
                    std::to_string(m.channels()) + " channels; expected " +
                    std::to_string(config_.width) + " x " + std::to_string(config_.height) + " BGR";
      return Status::kBadReply;
    }
  }
  frame->t_s = now - t0_;
  frame->sequence = sequence_++;
  frame->laser_encoder_count = 0;
  frame->laser_on = false;
  frame->head = {};
  if (latch_) {
    ExposureLatch latch;
    const Status s = latch_(&latch);
    if (s != Status::kOk) {
      last_error_ = "laser board: no latch for this frame (" + std::string(ToString(s)) + ")";
      return s;
    }
    frame->laser_encoder_count = latch.encoder_count;
    frame->laser_on = latch.laser_on;
  }
  if (head_ != nullptr) {
    device::HeadState head;
    const Status s = head_->Read(&head);
    if (s != Status::kOk) {
      last_error_ = "head: no reading for this frame (" + std::string(ToString(s)) + ")";
      return s;
    }
    frame->head = head.q;
  }
  return Status::kOk;
}

}  // namespace hgrasp::drivers
