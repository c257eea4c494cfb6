// The twin behind the real wires, end to end: with the laser sweeping at full speed, every frame
// the real camera driver grabs (GstStereoCamera over the twin's GStreamer streams, latch_pairing
// offset) carries exactly the encoder count the twin latched at that frame's exposure, read
// back through the real LaserBoard driver on the twin's laser_board pty.

#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "camera/gst_stereo_camera.h"
#include "camera/gst_stereo_server.h"
#include "common/paths.h"
#include "laser_board/board_devices.h"
#include "laser_board/laser_board.h"
#include "serial/serial_port.h"
#include "sim/twin/twin.h"
#include "tests/support/status.h"
#include "twin_rig.h"

namespace hgrasp::sim {
namespace {

using device::Status;
using testing::Clock;
using testing::Since;

struct Grabbed {
  double t_s = 0.0;
  std::int32_t count = 0;
  bool laser_on = false;
};

TEST(TwinLatchTest, EveryFramesEncoderCountIsTheTwinsAtItsExposure) {
  testing::TwinRig rig(ResolveDataPath("scenarios/default.yaml"));
  ASSERT_TRUE(rig.ok) << rig.error;
  drivers::LaserBoard& board = *rig.board;
  drivers::BoardStripeLaser& laser = *rig.laser;
  drivers::GstStereoCamera* camera = rig.camera.get();
  Twin& twin = *rig.twin;

  // Full speed, back and forth between the limits (the twin's board: -4500 ... 4500 counts).
  const double top = board.options().max_speed_counts_s;
  ASSERT_EQ(top, 9000.0);
  constexpr std::int32_t kLimit = 4500;
  ASSERT_EQ(laser.SetLaser(true), Status::kOk);
  std::int32_t target = kLimit;
  ASSERT_EQ(laser.MoveTo(target, top), Status::kOk);

  device::StereoFrame frame;
  const drivers::GstCameraStats stats0 = camera->stats();

  constexpr int kFrames = 150;
  std::vector<Grabbed> grabbed;
  std::vector<std::string> failures;
  const Clock::time_point t0 = Clock::now();
  while (static_cast<int>(grabbed.size()) < kFrames && Since(t0) < 20.0) {
    const Status s = camera->Grab(&frame);
    if (s != Status::kOk) {
      failures.push_back(std::string(ToString(s)) + ": " + camera->last_error());
      continue;
    }
    grabbed.push_back({frame.t_s, frame.laser_encoder_count, frame.laser_on});
    device::StripeLaserState st;
    if (laser.Read(&st) == Status::kOk && !st.moving) {
      target = -target;
      const Status m = laser.MoveTo(target, top);
      if (m != Status::kOk) failures.push_back("MoveTo: " + std::string(ToString(m)));
    }
  }
  const double grab_s = Since(t0);
  const drivers::GstCameraStats stats1 = camera->stats();
  EXPECT_OK(laser.Stop());
  EXPECT_OK(laser.SetLaser(false));
  rig.StopTwin();

  const std::vector<TwinExposure>& exposures = twin.exposures();
  const TwinFrameCounts counts = twin.frame_counts();
  std::ostringstream summary;
  summary << grabbed.size() << " frames grabbed in " << grab_s << " s; twin: " << counts.exposures
          << " exposures, " << counts.rendered << " rendered, " << counts.overruns
          << " overruns, mean render "
          << (counts.rendered ? 1e3 * counts.render_s / counts.rendered : 0.0) << " ms, max "
          << 1e3 * counts.max_render_s << " ms, max lag " << 1e3 * counts.max_lag_s
          << " ms; driver: " << stats1.frames_lost[0] - stats0.frames_lost[0] << " left / "
          << stats1.frames_lost[1] - stats0.frames_lost[1] << " right frames lost, "
          << failures.size() << " failed grabs";
  if (!failures.empty()) summary << " (first: " << failures.front() << ")";
  SCOPED_TRACE(summary.str());
  std::printf("%s\n", summary.str().c_str());
  ASSERT_EQ(static_cast<int>(grabbed.size()), kFrames);

  // Every frame: the exposure of the same time, its count and laser state.
  int mismatches = 0;
  std::ostringstream first;
  std::vector<std::size_t> index(grabbed.size());
  for (std::size_t i = 0; i < grabbed.size(); ++i) {
    const Grabbed& g = grabbed[i];
    const auto it = std::lower_bound(exposures.begin(), exposures.end(), g.t_s - 1e-6,
                                     [](const TwinExposure& e, double t) { return e.t_s < t; });
    std::string what;
    if (it == exposures.end() || std::abs(it->t_s - g.t_s) > 1e-6) {
      what = "no exposure of the twin at its time";
    } else {
      index[i] = static_cast<std::size_t>(it - exposures.begin());
      if (it->encoder_count != g.count || it->laser_on != g.laser_on) {
        std::ostringstream w;
        w << "the twin latched " << it->encoder_count << (it->laser_on ? " (laser on)" : " (off)")
          << " at frame " << it->frame;
        what = w.str();
      }
    }
    if (!what.empty()) {
      if (++mismatches <= 8) {
        first << "\n  frame " << i << " t_s " << g.t_s << ": count " << g.count
              << (g.laser_on ? " (laser on)" : " (off)") << "; " << what;
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << "frames whose latch is not the twin's at their exposure:"
                           << first.str();

  // The counts really moved fast: full speed is 360 counts a frame.
  std::vector<int> steps;
  for (std::size_t i = 1; i < grabbed.size(); ++i) {
    steps.push_back(std::abs(grabbed[i].count - grabbed[i - 1].count));
  }
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  EXPECT_GT(steps[steps.size() / 2], 200) << "median |count step| between consecutive frames";
  const auto dark =
      std::count_if(grabbed.begin(), grabbed.end(), [](const Grabbed& g) { return !g.laser_on; });
  EXPECT_EQ(dark, 0) << "frames grabbed with the laser off (it was switched on before them)";

  // At most 10 % of the frames the twin rendered between the first and the last grabbed were
  // lost on the way (the streams, the driver's one-frame queue, the pairing). The exposures the
  // twin did not render (its overruns) never left it: they are counted here and reported, not
  // held against the path. On the 2-core machine with llvmpipe each reversal of the motor at
  // full speed costs the twin two or three frames: the reaction of the laser's ramp moves the
  // head's pan and tilt by 1-2 urad, over the render cache's 1 urad, and a full re-render takes
  // 50-150 ms there.
  if (mismatches == 0) {
    std::uint64_t rendered = 0;
    for (std::size_t k = index.front(); k <= index.back(); ++k) rendered += exposures[k].rendered;
    const std::uint64_t span = index.back() - index.front() + 1;
    RecordProperty("twin_overruns_in_span", static_cast<int>(span - rendered));
    EXPECT_GE(static_cast<double>(grabbed.size()), 0.9 * static_cast<double>(rendered))
        << grabbed.size() << " frames grabbed of the " << rendered << " the twin rendered from "
        << "frame " << exposures[index.front()].frame << " to " << exposures[index.back()].frame
        << " (" << span - rendered << " exposures not rendered: overruns)";
  }
}

}  // namespace
}  // namespace hgrasp::sim
