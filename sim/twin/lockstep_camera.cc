#include "sim/twin/lockstep_camera.h"

#include <utility>

namespace hgrasp::sim {

using device::Status;

FrameSink LockstepFrames::SinkFor(const std::shared_ptr<LockstepFrames>& frames) {
  return [frames](int camera, const cv::Mat& bgr, std::uint64_t number, double t_s) {
    frames->Put(camera, bgr, number, t_s);
  };
}

void LockstepFrames::Put(int camera, const cv::Mat& bgr, std::uint64_t number, double t_s) {
  if (pending_[camera]) ++lost_[camera];
  // A copy of its own: the renderer reuses its buffers, and callers keep frames.
  pending_[camera] = Frame{number, t_s, bgr.clone()};
}

LockstepCamera::LockstepCamera(SimClock& clock, std::shared_ptr<LockstepFrames> frames,
                               std::function<bool()> develop, drivers::LatchSource latch,
                               device::Head* head, double frame_timeout_s)
    : clock_(clock),
      frames_(std::move(frames)),
      develop_(std::move(develop)),
      latch_(std::move(latch)),
      head_(head),
      frame_timeout_s_(frame_timeout_s) {}

Status LockstepCamera::Grab(device::StereoFrame* frame) {
  LockstepFrames& f = *frames_;
  for (int drops = 0;; ++drops) {
    const Clock::TimePoint deadline = clock_.Now() + Clock::FromSeconds(frame_timeout_s_);
    // The newest exposure taken before this call, else the next one: developed as it comes.
    auto ready = [&] {
      if (develop_) develop_();
      return f.pending(0) && f.pending(1);
    };
    if (!clock_.RunUntil(deadline, ready)) {
      last_error_ = std::string(f.pending(0) ? "right" : "left") + " camera: no frame for " +
                    std::to_string(frame_timeout_s_) + " s (frame_timeout_s)";
      return Status::kTimeout;
    }
    const std::uint64_t a = f.pending(0)->number, b = f.pending(1)->number;
    const drivers::PairStep step = drivers::NextPairStep(a, b, drops, drivers::kMaxPairingDrops);
    if (step == drivers::PairStep::kPaired) break;
    const int older = step == drivers::PairStep::kDropLeft    ? 0
                      : step == drivers::PairStep::kDropRight ? 1
                                                              : drivers::OlderOf(a, b);
    f.pending(older).reset();
    ++unpaired_[older];
    if (step == drivers::PairStep::kUnpairable) {
      last_error_ = drivers::UnpairableMessage(a, b, drivers::kMaxPairingDrops);
      return Status::kBadReply;
    }
  }
  LockstepFrames::Frame left = std::move(*f.pending(0));
  LockstepFrames::Frame right = std::move(*f.pending(1));
  f.pending(0).reset();
  f.pending(1).reset();
  frame->left = std::move(left.bgr);
  frame->right = std::move(right.bgr);
  frame->t_s = left.t_s;
  frame->sequence = sequence_++;
  ++pairs_;
  return drivers::AnnotateExposure(drivers::LatchPairing::kOffset, 0, left.number, latch_, head_,
                                   frame, &last_error_);
}

}  // namespace hgrasp::sim
