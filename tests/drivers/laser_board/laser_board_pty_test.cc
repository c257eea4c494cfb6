// The laser board driver on its real transport: a pty to the emulator (EmulatorHost), in
// wall-clock time (label realtime). The pipeline's thread drives the seam while a camera thread
// asks for frame latches: no call fails and every command is executed once, whatever the load.
// Everything else the driver does is tested in simulated time (laser_board_driver_test.cc).

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "laser_board_rig.h"

namespace hgrasp::drivers {
namespace {

using device::Side;
using device::Status;
using testing::BoardRig;

TEST(LaserBoardPty, TheSeamAndACameraThreadShareTheDriver) {
  BoardRig rig("pty_shared");
  auto board = std::make_shared<LaserBoard>(rig.OpenPort());
  BoardStripeLaser laser(board);
  BoardLeds leds(board);
  // The first VSYNC comes at 40 ms of the emulator's clock.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::atomic<int> failures{0};
  std::thread camera([&] {
    for (int i = 0; i < 200; ++i) {
      FrameLatch l;
      if (board->LatestFrameLatch(&l) != Status::kOk) ++failures;
    }
  });
  for (int i = 0; i < 100; ++i) {
    device::StripeLaserState s;
    if (laser.Read(&s) != Status::kOk) ++failures;
    if (leds.Set(i % 2 ? Side::kLeft : Side::kRight, static_cast<std::uint32_t>(i % 64)) !=
        Status::kOk) {
      ++failures;
    }
  }
  camera.join();
  EXPECT_EQ(failures.load(), 0);
  EXPECT_EQ(rig.Executed().size(), 100u);
  EXPECT_EQ(board->stats().retransmissions, 0u);
}

}  // namespace
}  // namespace hgrasp::drivers
