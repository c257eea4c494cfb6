#pragma once
/// @file What every stereo camera of the robot does with its frames, whatever carries them: the
/// left and right frames of one exposure paired by frame number, and the pair given what the
/// laser board latched at that exposure and the head's joints. GstStereoCamera (GStreamer
/// appsinks) and the twin's lockstep camera (frames handed over in simulated time) share it,
/// so only the transport differs. No GStreamer here.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "device/head.h"
#include "device/status.h"
#include "device/stereo_camera.h"

namespace hgrasp::drivers {

/// What the laser board latched at a camera frame (its vertical sync).
struct ExposureLatch {
  std::uint32_t frame = 0;         ///< the board's frame counter
  std::int32_t encoder_count = 0;  ///< laser motor encoder at that frame
  bool laser_on = false;
};
/// Asks the laser board for the latch of board frame `*frame`, or its newest latch when `frame`
/// is empty. kRejected when that frame's latch is no longer (or not yet) on the board.
using LatchSource =
    std::function<device::Status(std::optional<std::uint32_t> frame, ExposureLatch*)>;

/// Which of the board's latches goes with a frame.
enum class LatchPairing {
  kLatest,  ///< the board's newest latch at grab time
  kOffset,  ///< the latch of board frame = the frame's number + frame_offset
};

/// The most frames a camera drops from one stream to find the other's frame number: streams
/// further apart than this do not count the same frames (kUnpairable, kBadReply).
inline constexpr int kMaxPairingDrops = 8;

/// The next step in pairing the two cameras' pending frames.
enum class PairStep {
  kPaired,      ///< the two go together: same number, or a camera's frame carries none
  kDropLeft,    ///< the left is older: drop it and take the left camera's next
  kDropRight,   ///< the right is older: likewise
  kUnpairable,  ///< further apart than max_drops, or max_drops already dropped: drop the
                ///< older (kDropLeft's or kDropRight's) and report kBadReply
};

/// Left and right frame numbers (nullopt: that frame carries none, and frames are then paired
/// as they come); `drops`: frames dropped so far for this pair. Pure.
PairStep NextPairStep(std::optional<std::uint64_t> left, std::optional<std::uint64_t> right,
                      int drops, int max_drops);
/// For kUnpairable: which to drop (0 left, 1 right: the older) and the message naming both
/// numbers and the limit.
int OlderOf(std::uint64_t left, std::uint64_t right);
std::string UnpairableMessage(std::uint64_t left, std::uint64_t right, int max_drops);

/// Fills `frame`'s laser_encoder_count and laser_on from `latch` (left 0 / false when `latch` is
/// empty: no board) and its head joints from `head` (left 0 when null). `number` is the left
/// frame's number: with kOffset the latch of board frame number + frame_offset (mod 2^32, the
/// board's counter wraps) is asked for, and a frame without a number is kBadReply. A failing
/// latch or head read returns its status and sets *error (the frame's images are kept).
device::Status AnnotateExposure(LatchPairing pairing, int frame_offset,
                                std::optional<std::uint64_t> number, const LatchSource& latch,
                                device::Head* head, device::StereoFrame* frame, std::string* error);

}  // namespace hgrasp::drivers
