// The pairing every stereo camera shares (camera/exposure_pairing.h), on cases worked by hand:
// which frame goes, when two streams cannot be paired, and what a pair is given from the board
// and the head.

#include "camera/exposure_pairing.h"

#include <gtest/gtest.h>

#include <deque>
#include <optional>
#include <vector>

namespace hgrasp::drivers {
namespace {

using device::Status;

// Two queues of frame numbers, paired as a camera's Grab pairs them: the pairs taken, and the
// frames dropped from each side.
struct Pairing {
  std::vector<std::uint64_t> pairs;
  int dropped[2] = {0, 0};
  int unpairable = 0;
};
Pairing PairAll(std::deque<std::uint64_t> left, std::deque<std::uint64_t> right, int max_drops) {
  Pairing p;
  std::deque<std::uint64_t>* q[2] = {&left, &right};
  int drops = 0;
  while (!left.empty() && !right.empty()) {
    const PairStep step = NextPairStep(left.front(), right.front(), drops, max_drops);
    if (step == PairStep::kPaired) {
      p.pairs.push_back(left.front());
      left.pop_front();
      right.pop_front();
      drops = 0;
      continue;
    }
    const int older = step == PairStep::kDropLeft    ? 0
                      : step == PairStep::kDropRight ? 1
                                                     : OlderOf(left.front(), right.front());
    q[older]->pop_front();
    ++p.dropped[older];
    if (step == PairStep::kUnpairable) {
      ++p.unpairable;
      drops = 0;
    } else {
      ++drops;
    }
  }
  return p;
}

TEST(ExposurePairing, EqualNumbersPairAndTheOlderIsDropped) {
  EXPECT_EQ(NextPairStep(7, 7, 0, 8), PairStep::kPaired);
  EXPECT_EQ(NextPairStep(5, 7, 0, 8), PairStep::kDropLeft);
  EXPECT_EQ(NextPairStep(9, 7, 0, 8), PairStep::kDropRight);
  // A frame without a number pairs with whatever the other camera has.
  EXPECT_EQ(NextPairStep(std::nullopt, 7, 0, 8), PairStep::kPaired);
  EXPECT_EQ(NextPairStep(3, std::nullopt, 0, 8), PairStep::kPaired);
  // Left lost frame 11, right lost 13 and 14: 10, 12, 15 pair; 11 and 13, 14 go.
  const Pairing p = PairAll({10, 11, 12, 13, 14, 15}, {10, 12, 13, 14, 15}, 8);
  EXPECT_EQ(p.pairs, (std::vector<std::uint64_t>{10, 12, 13, 14, 15}));
  EXPECT_EQ(p.dropped[0], 1);
  EXPECT_EQ(p.dropped[1], 0);
  EXPECT_EQ(p.unpairable, 0);
}

TEST(ExposurePairing, StreamsTooFarApartAreUnpairable) {
  // 9 apart with at most 8 drops: unpairable at once, the older dropped.
  EXPECT_EQ(NextPairStep(1, 10, 0, 8), PairStep::kUnpairable);
  EXPECT_EQ(OlderOf(1, 10), 0);
  EXPECT_EQ(OlderOf(10, 1), 1);
  // 8 apart: eight drops pair them; after eight drops in one Grab, no ninth.
  EXPECT_EQ(NextPairStep(1, 9, 0, 8), PairStep::kDropLeft);
  EXPECT_EQ(NextPairStep(8, 9, 7, 8), PairStep::kDropLeft);
  EXPECT_EQ(NextPairStep(8, 9, 8, 8), PairStep::kUnpairable);
  EXPECT_EQ(UnpairableMessage(1, 10, 8),
            "cameras: the left frame 1 and the right frame 10 do not pair (the streams' frame "
            "numbers are 9 apart; at most 8 frames are dropped to pair them)");
}

class FixedHead final : public device::Head {
 public:
  Status status = Status::kOk;
  device::HeadJoints q{0.1, -0.2, 0.03};
  Status MoveTo(const device::HeadJoints&) override { return Status::kOk; }
  Status Stop() override { return Status::kOk; }
  Status Read(device::HeadState* s) override {
    if (status == Status::kOk) s->q = q;
    return status;
  }
};

TEST(ExposurePairing, APairIsGivenTheLatchOfItsFrameAndTheHead) {
  std::vector<std::optional<std::uint32_t>> asked;
  LatchSource board = [&](std::optional<std::uint32_t> frame, ExposureLatch* l) {
    asked.push_back(frame);
    if (frame && *frame == 99) return Status::kRejected;  // no longer on the board
    l->frame = frame.value_or(41);
    l->encoder_count = frame ? static_cast<std::int32_t>(*frame) * 10 : -5;
    l->laser_on = true;
    return Status::kOk;
  };
  FixedHead head;
  device::StereoFrame f;
  std::string error;
  // Latest: the board's newest latch, whatever the frame's number.
  ASSERT_EQ(AnnotateExposure(LatchPairing::kLatest, 0, 12, board, &head, &f, &error), Status::kOk);
  EXPECT_EQ(f.laser_encoder_count, -5);
  EXPECT_TRUE(f.laser_on);
  EXPECT_EQ(f.head.pan, 0.1);
  EXPECT_EQ(f.head.tilt, -0.2);
  EXPECT_EQ(f.head.verge, 0.03);
  // Offset: board frame = number + offset; 2^32 + 3 wraps to 3.
  ASSERT_EQ(AnnotateExposure(LatchPairing::kOffset, 2, 10, board, &head, &f, &error), Status::kOk);
  EXPECT_EQ(f.laser_encoder_count, 120);
  ASSERT_EQ(
      AnnotateExposure(LatchPairing::kOffset, 0, (1ull << 32) + 3, board, nullptr, &f, &error),
      Status::kOk);
  EXPECT_EQ(f.laser_encoder_count, 30);
  EXPECT_EQ(f.head.pan, 0.0);  // no head: zeros
  EXPECT_EQ(asked, (std::vector<std::optional<std::uint32_t>>{std::nullopt, 12u, 3u}));
  // A latch gone from the board, a frame without a number, a head that does not answer.
  EXPECT_EQ(AnnotateExposure(LatchPairing::kOffset, 0, 99, board, &head, &f, &error),
            Status::kRejected);
  EXPECT_EQ(error, "laser board: no latch for this frame (board frame 99) (rejected)");
  EXPECT_EQ(AnnotateExposure(LatchPairing::kOffset, 0, std::nullopt, board, &head, &f, &error),
            Status::kBadReply);
  head.status = Status::kTimeout;
  EXPECT_EQ(AnnotateExposure(LatchPairing::kLatest, 0, 5, board, &head, &f, &error),
            Status::kTimeout);
  EXPECT_EQ(error, "head: no reading for this frame (timeout)");
  // No board, no head: zeros.
  head.status = Status::kOk;
  ASSERT_EQ(AnnotateExposure(LatchPairing::kOffset, 0, std::nullopt, {}, nullptr, &f, &error),
            Status::kOk);
  EXPECT_EQ(f.laser_encoder_count, 0);
  EXPECT_FALSE(f.laser_on);
}

}  // namespace
}  // namespace hgrasp::drivers
