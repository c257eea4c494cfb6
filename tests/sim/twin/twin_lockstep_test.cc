// The twin in lockstep (TwinOptions::lockstep): the real drivers on its in-process lines and
// the lockstep camera, all on one SimClock in this thread. What the wall-clock twin's tests
// check under the load of the machine, here exactly: every frame's encoder count is the one the
// twin latched at its exposure; and one scenario gives one run, byte for byte.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/clock.h"
#include "common/paths.h"
#include "laser_board/board_devices.h"
#include "laser_board/laser_board.h"
#include "sensorhand/sensorhand_hand.h"
#include "sim/twin/lockstep_camera.h"
#include "sim/twin/twin.h"
#include "tests/support/status.h"
#include "val2/val2_arm.h"

namespace hgrasp::sim {
namespace {

using device::Status;

// The twin of the default scenario in lockstep, the real laser board, right arm and right hand
// drivers on its lines, and the lockstep camera with the board's latches. Members in the order
// they must go: the drivers before the twin, the twin before its clock.
struct LockstepRig {
  LockstepRig() {
    TwinOptions options;
    options.lockstep = &clock;
    twin = std::make_unique<Twin>(LoadScenario(ResolveDataPath("scenarios/default.yaml")), options,
                                  LockstepFrames::SinkFor(frames));
    board = std::make_shared<drivers::LaserBoard>(twin->HostLink("laser_board"),
                                                  drivers::LaserBoardOptions{}, clock);
    laser = std::make_unique<drivers::BoardStripeLaser>(board);
    arm = std::make_unique<drivers::Val2Arm>(twin->HostLink("arm_right"), drivers::Val2Options{},
                                             clock);
    hand = std::make_unique<drivers::SensorHandHand>(twin->HostLink("hand_right"),
                                                     drivers::SensorHandOptions{}, clock);
    Twin* t = twin.get();
    camera = std::make_unique<LockstepCamera>(
        clock, frames, [t] { return t->Develop(); }, drivers::BoardLatchSource(board), nullptr);
  }
  ~LockstepRig() {
    camera.reset();
    hand.reset();
    arm.reset();
    laser.reset();
    board.reset();
    twin.reset();
  }
  SimClock clock;
  std::shared_ptr<LockstepFrames> frames = std::make_shared<LockstepFrames>();
  std::unique_ptr<Twin> twin;
  std::shared_ptr<drivers::LaserBoard> board;
  std::unique_ptr<drivers::BoardStripeLaser> laser;
  std::unique_ptr<drivers::Val2Arm> arm;
  std::unique_ptr<drivers::SensorHandHand> hand;
  std::unique_ptr<LockstepCamera> camera;
};

struct Grabbed {
  std::uint64_t sequence = 0;
  double t_s = 0.0;
  std::int32_t count = 0;
  bool laser_on = false;
  double mean_bgr = 0.0;  // the images' mean value: the pixels, in one number
};

// The laser sweeping at full speed between its limits while the camera grabs `n` frames.
std::vector<Grabbed> Sweep(LockstepRig& rig, int n, std::vector<std::string>* failures) {
  const double top = rig.board->options().max_speed_counts_s;
  std::int32_t target = 4500;
  std::vector<Grabbed> grabbed;
  if (rig.laser->SetLaser(true) != Status::kOk) failures->push_back("SetLaser");
  if (rig.laser->MoveTo(target, top) != Status::kOk) failures->push_back("MoveTo");
  device::StereoFrame frame;
  while (static_cast<int>(grabbed.size()) < n && failures->size() < 10) {
    const Status s = rig.camera->Grab(&frame);
    if (s != Status::kOk) {
      failures->push_back(std::string(ToString(s)) + ": " + rig.camera->last_error());
      continue;
    }
    const cv::Scalar l = cv::mean(frame.left), r = cv::mean(frame.right);
    grabbed.push_back({frame.sequence, frame.t_s, frame.laser_encoder_count, frame.laser_on,
                       (l[0] + l[1] + l[2] + r[0] + r[1] + r[2]) / 6.0});
    device::StripeLaserState st;
    if (rig.laser->Read(&st) == Status::kOk && !st.moving) {
      target = -target;
      if (rig.laser->MoveTo(target, top) != Status::kOk) failures->push_back("MoveTo");
    }
  }
  EXPECT_OK(rig.laser->Stop());
  EXPECT_OK(rig.laser->SetLaser(false));
  return grabbed;
}

TEST(TwinLockstep, EveryFramesEncoderCountIsTheTwinsAtItsExposure) {
  LockstepRig rig;
  std::vector<std::string> failures;
  const auto wall0 = std::chrono::steady_clock::now();
  const std::vector<Grabbed> grabbed = Sweep(rig, 60, &failures);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  ASSERT_TRUE(failures.empty()) << failures.front();
  ASSERT_EQ(grabbed.size(), 60u);
  const std::vector<TwinExposure>& exposures = rig.twin->exposures();
  const TwinFrameCounts counts = rig.twin->frame_counts();
  std::printf(
      "lockstep: %zu frames grabbed, %.2f s of twin time in %.2f s wall; twin: %llu exposures, "
      "%llu rendered, %llu overruns; camera: %llu / %llu frames not grabbed (left / right)\n",
      grabbed.size(), rig.twin->time(), wall, static_cast<unsigned long long>(counts.exposures),
      static_cast<unsigned long long>(counts.rendered),
      static_cast<unsigned long long>(counts.overruns),
      static_cast<unsigned long long>(rig.frames->lost(0)),
      static_cast<unsigned long long>(rig.frames->lost(1)));
  EXPECT_EQ(counts.overruns, 0u);  // in simulated time the renderer never falls behind
  // One time base: the drivers' clock reads the world's time (to the nanosecond the clock
  // counts in; the world sums its float timesteps).
  EXPECT_NEAR(rig.clock.NowSeconds(), rig.twin->time(), 1e-9);
  int mismatches = 0;
  for (const Grabbed& g : grabbed) {
    const auto it = std::find_if(exposures.begin(), exposures.end(),
                                 [&](const TwinExposure& e) { return e.t_s == g.t_s; });
    ASSERT_NE(it, exposures.end()) << "no exposure at " << g.t_s;
    if (it->encoder_count != g.count || it->laser_on != g.laser_on) ++mismatches;
  }
  EXPECT_EQ(mismatches, 0);
  // The counts really moved fast: full speed is 360 counts a frame.
  std::vector<int> steps;
  for (std::size_t i = 1; i < grabbed.size(); ++i) {
    steps.push_back(std::abs(grabbed[i].count - grabbed[i - 1].count));
  }
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  EXPECT_GT(steps[steps.size() / 2], 200);
}

// Everything a run leaves that does not measure the machine: the twin's report without its
// render timings, the drivers' command logs, the frames grabbed.
std::string Session(double* twin_s) {
  LockstepRig rig;
  std::string out;
  device::ArmState a;
  EXPECT_EQ(rig.arm->Read(&a), Status::kOk);
  device::Joint6 q = a.q;
  q[0] += 0.05;
  q[2] -= 0.03;
  EXPECT_EQ(rig.arm->MoveJoints(q), Status::kOk);
  for (int i = 0; i < 100 && rig.arm->Read(&a) == Status::kOk && a.moving; ++i) {
    rig.clock.SleepFor(0.05);
  }
  EXPECT_FALSE(a.moving);
  EXPECT_EQ(rig.hand->Open(0.05), Status::kOk);
  EXPECT_TRUE(rig.hand->WaitIdle(3.0));
  std::vector<std::string> failures;
  for (const Grabbed& g : Sweep(rig, 20, &failures)) {
    char line[160];
    std::snprintf(line, sizeof line, "%llu %.6f %d %d %.9f\n",
                  static_cast<unsigned long long>(g.sequence), g.t_s, g.count, g.laser_on,
                  g.mean_bgr);
    out += line;
  }
  EXPECT_TRUE(failures.empty());
  for (const auto& e : rig.arm->command_log().Snapshot()) out += e.command + "\n";
  out += std::to_string(rig.hand->command_log().Snapshot().size()) + " hand commands\n";
  out += std::to_string(rig.board->command_log().Snapshot().size()) + " board commands\n";
  nlohmann::json report = rig.twin->Report();
  report["frames"].erase("mean_render_ms");
  report["frames"].erase("max_render_ms");
  out += report.dump();
  *twin_s = rig.twin->time();
  return out;
}

TEST(TwinLockstep, OneScenarioOneRun) {
  double t1 = 0.0, t2 = 0.0;
  const auto wall0 = std::chrono::steady_clock::now();
  const std::string first = Session(&t1);
  const std::string second = Session(&t2);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf("two sessions of %.2f s twin time each in %.2f s wall; %zu bytes of record\n", t1,
              wall, first.size());
  EXPECT_GT(t1, 1.0);
  EXPECT_EQ(t1, t2);
  EXPECT_EQ(first, second);
}

}  // namespace
}  // namespace hgrasp::sim
