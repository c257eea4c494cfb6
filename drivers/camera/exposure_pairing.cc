#include "camera/exposure_pairing.h"

namespace hgrasp::drivers {

using device::Status;

PairStep NextPairStep(std::optional<std::uint64_t> left, std::optional<std::uint64_t> right,
                      int drops, int max_drops) {
  if (!left || !right || *left == *right) return PairStep::kPaired;
  const std::uint64_t gap = *left < *right ? *right - *left : *left - *right;
  if (gap > static_cast<std::uint64_t>(max_drops) || drops >= max_drops) {
    return PairStep::kUnpairable;
  }
  return *left < *right ? PairStep::kDropLeft : PairStep::kDropRight;
}

int OlderOf(std::uint64_t left, std::uint64_t right) { return left < right ? 0 : 1; }

std::string UnpairableMessage(std::uint64_t left, std::uint64_t right, int max_drops) {
  const std::uint64_t gap = left < right ? right - left : left - right;
  return "cameras: the left frame " + std::to_string(left) + " and the right frame " +
         std::to_string(right) + " do not pair (the streams' frame numbers are " +
         std::to_string(gap) + " apart; at most " + std::to_string(max_drops) +
         " frames are dropped to pair them)";
}

Status AnnotateExposure(LatchPairing pairing, int frame_offset, std::optional<std::uint64_t> number,
                        const LatchSource& latch, device::Head* head, device::StereoFrame* frame,
                        std::string* error) {
  frame->laser_encoder_count = 0;
  frame->laser_on = false;
  frame->head = {};
  if (latch) {
    std::optional<std::uint32_t> wanted;
    if (pairing == LatchPairing::kOffset) {
      if (!number) {
        *error =
            "left camera: the frame carries no frame number (buffer offset), which "
            "latch_pairing offset needs";
        return Status::kBadReply;
      }
      // The board's counter is 32 bits: it wraps, and so does the sum.
      wanted = static_cast<std::uint32_t>(
          *number + static_cast<std::uint64_t>(static_cast<std::int64_t>(frame_offset)));
    }
    ExposureLatch l;
    const Status s = latch(wanted, &l);
    if (s != Status::kOk) {
      *error = "laser board: no latch for this frame";
      if (wanted) error->append(" (board frame ").append(std::to_string(*wanted)).append(")");
      error->append(" (").append(ToString(s)).append(")");
      return s;
    }
    frame->laser_encoder_count = l.encoder_count;
    frame->laser_on = l.laser_on;
  }
  if (head != nullptr) {
    device::HeadState h;
    const Status s = head->Read(&h);
    if (s != Status::kOk) {
      *error = "head: no reading for this frame (" + std::string(ToString(s)) + ")";
      return s;
    }
    frame->head = h.q;
  }
  return Status::kOk;
}

}  // namespace hgrasp::drivers
