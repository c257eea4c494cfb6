#include "camera/gst_stereo_camera.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

namespace hgrasp::drivers {
namespace {

using device::Status;

// A solid-colour test source at PAL rate, as the frame grabber delivers it.
std::string Pipeline(const std::string& pattern, int width = 320, int height = 240,
                     int buffers = -1) {
  return "videotestsrc is-live=true pattern=" + pattern +
         " num-buffers=" + std::to_string(buffers) +
         " ! video/x-raw,format=BGR,width=" + std::to_string(width) +
         ",height=" + std::to_string(height) + ",framerate=25/1 ! appsink max-buffers=2 drop=true";
}

class FixedHead final : public device::Head {
 public:
  Status Read(device::HeadState* state) override {
    ++reads;
    state->q = {0.1, -0.2, 0.03};
    return Status::kOk;
  }
  Status MoveTo(const device::HeadJoints&) override { return Status::kRejected; }
  Status Stop() override { return Status::kOk; }
  int reads = 0;
};

TEST(GstStereoCamera, GrabsBothCamerasWithTheBoardsLatchAndTheHead) {
  FixedHead head;
  std::uint32_t board_frame = 100;
  LatchSource latch = [&](std::optional<std::uint32_t> wanted, ExposureLatch* l) {
    EXPECT_FALSE(wanted);  // latch_pairing latest
    l->frame = board_frame++;
    l->encoder_count = static_cast<std::int32_t>(board_frame) * 7;
    l->laser_on = true;
    return Status::kOk;
  };
  std::string error;
  auto camera = GstStereoCamera::Open({Pipeline("red"), Pipeline("blue")}, latch, &head, &error);
  ASSERT_TRUE(camera) << error;
  device::StereoFrame frame;
  double first_t = 0.0;
  const int kFrames = 10;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_EQ(camera->Grab(&frame), Status::kOk) << camera->last_error();
    if (i == 0) first_t = frame.t_s;
    EXPECT_EQ(frame.sequence, static_cast<std::uint64_t>(i));
  }
  // 25 frames/s: the stamps are the streams' own (PTS), whole periods of 40 ms apart, at least
  // nine between the first and the last grab. A loaded machine only adds periods (the appsink
  // keeps the newest frame), so the count is a lower bound (this test runs in wall-clock time).
  const double periods = (frame.t_s - first_t) / 0.04;
  EXPECT_NEAR(periods, std::round(periods), 1e-6);
  EXPECT_GE(std::lround(periods), kFrames - 1);
  ASSERT_EQ(frame.left.size(), cv::Size(320, 240));
  ASSERT_EQ(frame.left.type(), CV_8UC3);
  const cv::Vec3b l = frame.left.at<cv::Vec3b>(120, 160), r = frame.right.at<cv::Vec3b>(120, 160);
  EXPECT_GT(l[2], 200);  // BGR: the left is red
  EXPECT_LT(l[0], 40);
  EXPECT_GT(r[0], 200);  // the right is blue
  EXPECT_LT(r[2], 40);
  EXPECT_EQ(frame.laser_encoder_count, static_cast<std::int32_t>(board_frame) * 7);
  EXPECT_TRUE(frame.laser_on);
  EXPECT_DOUBLE_EQ(frame.head.pan, 0.1);
  EXPECT_DOUBLE_EQ(frame.head.verge, 0.03);
  EXPECT_EQ(head.reads, kFrames);
}

TEST(GstStereoCamera, ReportsBadPipelinesFramesAndTheEndOfAStream) {
  std::string error;
  EXPECT_FALSE(
      GstStereoCamera::Open({Pipeline("red"), "nosuchelement ! appsink"}, {}, nullptr, &error));
  EXPECT_NE(error.find("right camera"), std::string::npos) << error;
  EXPECT_NE(error.find("nosuchelement"), std::string::npos) << error;

  auto wrong_size =
      GstStereoCamera::Open({Pipeline("red", 640, 480), Pipeline("red")}, {}, nullptr, &error);
  ASSERT_TRUE(wrong_size) << error;
  device::StereoFrame frame;
  EXPECT_EQ(wrong_size->Grab(&frame), Status::kBadReply);
  EXPECT_NE(wrong_size->last_error().find("640 x 480"), std::string::npos)
      << wrong_size->last_error();

  auto ending =
      GstStereoCamera::Open({Pipeline("red", 320, 240, 3), Pipeline("red")}, {}, nullptr, &error);
  ASSERT_TRUE(ending) << error;
  Status s = Status::kOk;
  int grabbed = 0;
  while (grabbed < 10 && (s = ending->Grab(&frame)) == Status::kOk) ++grabbed;
  EXPECT_EQ(grabbed, 3);
  EXPECT_EQ(s, Status::kDisconnected);
  EXPECT_NE(ending->last_error().find("left camera"), std::string::npos);

  LatchSource broken = [](std::optional<std::uint32_t>, ExposureLatch*) {
    return Status::kTimeout;
  };
  auto no_board =
      GstStereoCamera::Open({Pipeline("red"), Pipeline("red")}, broken, nullptr, &error);
  ASSERT_TRUE(no_board) << error;
  EXPECT_EQ(no_board->Grab(&frame), Status::kTimeout);
  EXPECT_NE(no_board->last_error().find("laser board"), std::string::npos);
}

}  // namespace
}  // namespace hgrasp::drivers
