// The whole task in the simulator over seeded random scenes (issues 7 and 19), judged against
// ground truth. A test of its own: the suite's longest, which CTest starts first (COST).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "grasp/grasp_planner.h"
#include "sim/random_scene.h"
#include "tests/task/task_sim_util.h"

namespace hgrasp::task {
namespace {

using testing::Print;
using testing::RunInSim;

// Issue 7's acceptance: over 20 seeded random scenes whose target the open hand can span, the
// servo brings the gripper within 5 mm and 2 deg of the planned grasp and the box comes up by
// task.lift and stays up for 2 s, in at least 95% of them (by the truth). Issue 19: no run says
// lifted when the box rose under 45 mm; the cameras confirm the lift in most (a box the hand
// and the forearm hide from the head is reported grasp_slipped: seeds 3 and 26, where not one
// of its cells is seen after the lift).
TEST(GraspTaskSim, RandomScenes) {
  const int scenes = 20;
  int good = 0, tried = 0, confirmed = 0, false_lifts = 0;
  for (int seed = 1, n = 0; n < scenes; ++seed) {
    const sim::Scenario scenario = sim::RandomBoxScene(seed);
    ++tried;
    const Eigen::Vector3d& size = scenario.objects[0].size_O;
    if (std::min(size.x(), size.y()) + 2 * grasp::GraspConfig{}.clearance_m >
        grasp::HandGeometry{}.max_opening_m) {
      continue;
    }
    ++n;
    const testing::SimOutcome o = RunInSim(scenario);
    Print("seed " + std::to_string(seed), o);
    good += o.TrulyGrasped();
    confirmed += o.Success();
    false_lifts += o.FalselyLifted(scenario.task->lift_m);
  }
  std::printf(
      "%d of %d scenes (seeds 1-%d) within 5 mm / 2 deg and held by truth; the cameras confirmed "
      "%d; %d said lifted falsely\n",
      good, scenes, tried, confirmed, false_lifts);
  EXPECT_GE(good, 0.95 * scenes);
  EXPECT_EQ(false_lifts, 0);
  EXPECT_GE(confirmed, 0.75 * scenes);
}

}  // namespace
}  // namespace hgrasp::task
