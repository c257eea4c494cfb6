// Visual servo benchmarks (issue 7): one servo step (LEDs in both images, stereo pairs guided by
// the prediction, triangulation, the pose fit, the Kalman filter and the control law) on one
// core, target at most 1 ms; and a whole `hgrasp run` of the default scenario through the task
// (look, plan, approach, servo, close, lift and hold), target at most 20 s wall on the 2-core
// machine.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>

#include "common/error.h"
#include "common/paths.h"
#include "servo/control_law.h"
#include "servo/gripper_tracker.h"
#include "sim/sim_devices.h"
#include "task/grasp_task.h"
#include "tests/servo/servo_sim_util.h"

namespace hgrasp::servo {
namespace {

sim::Scenario DefaultScenario() {
  setenv("HGRASP_ROOT", HGRASP_SOURCE_ROOT, 0);
  return sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
}

void BM_ServoStep(benchmark::State& state) {
  sim::SimRobot robot(DefaultScenario());
  device::RobotDevices dev = robot.TakeDevices();
  const auto head = robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  const auto cameras = robot::LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml"));
  const LedLayouts layouts = LoadLedLayouts(ResolveDataPath("calibration/sim/leds.yaml"));
  // The right gripper above the table in view, as at a pre-grasp.
  const device::Side side = device::Side::kRight;
  const auto q = testing::JointsFacingCamera(robot, dev, side, Eigen::Vector3d(0.28, -0.05, 0.16),
                                             Eigen::Vector3d(0.3, 0, -1), 0.3);
  if (!q) {
    state.SkipWithError("no joints for the benchmark pose");
    return;
  }
  HGRASP_DEMAND(dev.ArmOf(side).MoveJoints(*q) == device::Status::kOk);
  testing::Settle(dev, side, 6.0);
  GripperTracker tracker(side, layouts.Of(side), cameras, head);
  if (tracker.Initialise(*dev.leds, *dev.cameras) != TrackerStatus::kOk) {
    state.SkipWithError("tracker did not initialise");
    return;
  }
  device::StereoFrame frame;
  HGRASP_DEMAND(dev.cameras->Grab(&frame) == device::Status::kOk);
  Pose3 X_CT = tracker.pose();
  X_CT.translation() += Eigen::Vector3d(0.01, -0.02, 0.03);
  int measured = 0;
  for (auto _ : state) {
    frame.t_s += 0.04;
    measured += tracker.Track(frame) == TrackerStatus::kOk;
    benchmark::DoNotOptimize(ComputeServoCommand(tracker.pose(), X_CT));
  }
  state.counters["measured"] = benchmark::Counter(measured, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_ServoStep)->Unit(benchmark::kMicrosecond);

// The whole task on the default scenario, in process (what `hgrasp run` does, without writing
// the pictures and the video).
void BM_WholeRunDefaultScenario(benchmark::State& state) {
  const sim::Scenario scenario = DefaultScenario();
  for (auto _ : state) {
    sim::SimRobot robot(scenario);
    device::RobotDevices dev = robot.TakeDevices();
    task::TaskConfig config;
    config.target_color = scenario.task->target_color;
    config.lift_m = scenario.task->lift_m;
    task::GraspTask grasp(
        &dev,
        task::LoadRobotModel("calibration/sim/cameras.yaml", "calibration/sim/laser.yaml",
                             "calibration/sim/leds.yaml"),
        config);
    const task::TaskResult& r = grasp.Run();
    state.counters["lifted"] = r.lifted;
    state.counters["device_s"] = r.device_s;
    if (!r.ok()) state.SkipWithError(r.message.c_str());
  }
}
BENCHMARK(BM_WholeRunDefaultScenario)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace hgrasp::servo
