// The whole task in the simulator (issue 7), judged against ground truth.

#include <gtest/gtest.h>

#include <memory>

#include "common/paths.h"
#include "tests/task/task_sim_util.h"
#include "tests/task/timing_out_laser.h"

namespace hgrasp::task {
namespace {

using testing::Print;
using testing::RunInSim;

TEST(GraspTaskSim, DefaultScenarioIsGraspedAndTheSameSeedGivesTheSameRun) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  const testing::SimOutcome a = RunInSim(scenario, {}, {}, /*every_image=*/true);
  Print("default", a);
  EXPECT_TRUE(a.Success()) << a.result.message;
  EXPECT_GT(a.result.gripper_rise_m, 0.8 * scenario.task->lift_m);
  EXPECT_LT(a.result.gripper_rise_m, 1.2 * scenario.task->lift_m);
  // The cameras knew the box itself risen at least 45 mm, and the truth lies in what they left.
  ASSERT_TRUE(a.result.box_rise);
  EXPECT_GE(a.result.box_rise->min_m, 0.045);
  EXPECT_LE(a.result.box_rise->min_m, a.rise_m + 0.002);
  EXPECT_GE(a.result.box_rise->max_m, a.rise_m - 0.002);
  // Deterministic: the same scenario and seed give the same figures (timings aside), whether or
  // not the frames of the waits come with images.
  const testing::SimOutcome b = RunInSim(scenario, {}, {}, /*every_image=*/false);
  ASSERT_EQ(a.result.servo.size(), b.result.servo.size());
  for (std::size_t i = 0; i < a.result.servo.size(); ++i) {
    EXPECT_EQ(a.result.servo[i].iterations, b.result.servo[i].iterations);
    EXPECT_EQ(a.result.servo[i].final_error.translation_m,
              b.result.servo[i].final_error.translation_m);
    EXPECT_EQ(a.result.servo[i].final_error.rotation_rad,
              b.result.servo[i].final_error.rotation_rad);
  }
  EXPECT_EQ(a.result.gripper_rise_m, b.result.gripper_rise_m);
  ASSERT_TRUE(b.result.box_rise);
  EXPECT_EQ(a.result.box_rise->min_m, b.result.box_rise->min_m);
  EXPECT_EQ(a.result.box_rise->max_m, b.result.box_rise->max_m);
  EXPECT_EQ(a.result.device_s, b.result.device_s);
  EXPECT_EQ(a.result.measurements, b.result.measurements);
  EXPECT_EQ(a.rise_m, b.rise_m);
  ASSERT_TRUE(a.result.scan && b.result.scan);
  EXPECT_EQ(a.result.scan->points, b.result.scan->points);
  EXPECT_EQ(a.result.scan->rejected, b.result.scan->rejected);
  ASSERT_EQ(a.result.scene->boxes.size(), b.result.scene->boxes.size());
  for (std::size_t i = 0; i < a.result.scene->boxes.size(); ++i) {
    EXPECT_EQ(a.result.scene->boxes[i].X_WO.matrix(), b.result.scene->boxes[i].X_WO.matrix());
    EXPECT_EQ(a.result.scene->boxes[i].size_O, b.result.scene->boxes[i].size_O);
  }
}

// The frames grabbed only to wait for a move (here the scan's slew to its start) come without
// images when the sink does not need every image, and with them when it does.
TEST(GraspTaskSim, FramesOfTheWaitsComeWithoutImagesUnlessTheSinkNeedsEveryImage) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  for (const bool every_image : {true, false}) {
    sim::SimRobot robot(scenario);
    device::RobotDevices dev = robot.TakeDevices();
    TaskConfig config = testing::ConfigFor(scenario);
    config.sink_needs_every_image = every_image;
    int frames = 0, without = 0;
    GraspTask task(&dev, testing::SimRobotModel(), config,
                   [&](const device::StereoFrame& frame, const TaskView&) {
                     ++frames;
                     without += frame.left.empty() || frame.right.empty();
                   });
    ASSERT_TRUE(task.Look()) << task.result().message;
    std::printf("sink needs every image %d: %d of %d frames without images\n", every_image, without,
                frames);
    if (every_image) {
      EXPECT_EQ(without, 0);
    } else {
      EXPECT_GT(without, 0);
      EXPECT_LT(without, 20);  // the slew only: the sweep's frames all have theirs
    }
  }
}

// The paper's claim: no camera-to-arm calibration. The head is really mounted 2 cm and 3 deg
// away from where the kinematics (URDF) put it; the open-loop approach misses the pre-grasp by
// centimetres, and the servo still brings the hand onto the planned grasp.
// Issue 19: the lift is judged by the box the cameras see, not by the gripper. The heaviest box
// the scenario schema allows, gripped at 1 N: the fingers slide up its sides (2 pads x friction
// 1.5 x 1 N = 3 N against its 4.9 N weight) and stay on it, so the hand still holds something,
// and the gripper rose the whole lift. The old verdict said lifted.
TEST(GraspTaskSim, ABoxTheFingersSlideAlongIsGraspSlippedNotLifted) {
  sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  scenario.objects[0].mass = sim::kMaxMass;
  const testing::SimOutcome a =
      RunInSim(scenario, {}, {}, false, [](TaskConfig* c) { c->grip_force_n = 1.0; });
  Print("slides", a);
  EXPECT_EQ(a.result.failure, Failure::kGraspSlipped) << a.result.message;
  EXPECT_FALSE(a.result.lifted);
  EXPECT_LT(a.rise_m, 0.045);                 // truth: the box stayed low
  EXPECT_GT(a.result.gripper_rise_m, 0.045);  // the gripper did not
  EXPECT_GT(a.result.held_opening_m, 0.01);   // and the fingers still held the box
  ASSERT_TRUE(a.result.box_rise);
  EXPECT_LT(a.result.box_rise->min_m, 0.045);
  EXPECT_LE(a.result.box_rise->min_m, a.rise_m + 0.002);
}

// The heaviest box the schema allows, at the task's grip force (40 N: 2 pads x 1.5 x 40 N =
// 120 N of friction for its 4.9 N), is lifted and held, by truth and by the cameras.
TEST(GraspTaskSim, TheHeaviestBoxAllowedIsLiftedAndHeld) {
  sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  scenario.objects[0].mass = sim::kMaxMass;
  const testing::SimOutcome a = RunInSim(scenario, {}, {}, false);
  Print("heaviest", a);
  EXPECT_TRUE(a.Success()) << a.result.message;
  EXPECT_GE(a.rise_m, 0.045);
  ASSERT_TRUE(a.result.box_rise);
  EXPECT_GE(a.result.box_rise->min_m, 0.045);
  EXPECT_LE(a.result.box_rise->min_m, a.rise_m + 0.002);
}

TEST(GraspTaskSim, NoHandEyeCalibrationNeeded) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  sim::WorldOptions options;
  options.head_mount_error.linear() =
      Eigen::AngleAxisd(DegToRad(3.0), Eigen::Vector3d(1, -1, 1).normalized()).toRotationMatrix();
  options.head_mount_error.translation() = 0.02 * Eigen::Vector3d(1, 1, -1).normalized();
  const testing::SimOutcome o = RunInSim(scenario, options);
  Print("head mount 2 cm / 3 deg", o);
  std::printf("open-loop approach off the pre-grasp by %.1f mm %.2f deg\n",
              1e3 * o.after_approach.translation_m, RadToDeg(o.after_approach.rotation_rad));
  EXPECT_GT(o.after_approach.translation_m, 0.01);  // what calibration error alone does
  EXPECT_TRUE(o.Success()) << o.result.message;
  EXPECT_GT(o.result.servo.at(0).iterations, 0);  // the servo did the work
}

// The LEDs are hidden for 1 s in the middle of the servo: tracking is lost, the LEDs are found
// again by flashing, and the grasp goes on.
TEST(GraspTaskSim, RecoversFromHiddenLeds) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  bool hidden = false;
  double hidden_at = 0;
  const testing::SimOutcome o =
      RunInSim(scenario, {},
               [&](const device::StereoFrame& frame, const TaskView& view, sim::SimRobot& robot) {
                 if (!hidden && view.moment == "pregrasp_reached") {
                   hidden = true;
                   hidden_at = frame.t_s + 0.1;
                   robot.world().HideLeds(hidden_at, hidden_at + 1.0);
                 }
               });
  Print("LEDs hidden 1 s", o);
  ASSERT_TRUE(hidden);
  EXPECT_GE(o.result.recoveries, 1);
  EXPECT_TRUE(o.Success()) << o.result.message;
}

TEST(GraspTaskSim, AbsentTargetIsNoTarget) {
  sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  scenario.task->target_color = "green";
  const testing::SimOutcome o = RunInSim(scenario);
  EXPECT_EQ(o.result.failure, Failure::kNoTarget);
  EXPECT_EQ(o.result.message, "no green box found");
  EXPECT_FALSE(o.result.plan.has_value());
  EXPECT_EQ(ToString(o.result.failure), "no_target");
}

// Issue 16: the scan dropped the devices' statuses, so a laser board that stopped answering
// ended the task as no_target ("no box found"). Now: device_error naming the laser, laser off.
TEST(GraspTaskSim, ALaserThatTimesOutDuringTheScanIsADeviceError) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  auto laser = std::make_unique<hgrasp::testing::TimingOutLaser>(std::move(dev.laser), 40);
  const hgrasp::testing::TimingOutLaser* board = laser.get();
  dev.laser = std::move(laser);
  GraspTask task(&dev, testing::SimRobotModel(), testing::ConfigFor(scenario));
  EXPECT_FALSE(task.Look());
  EXPECT_EQ(task.result().failure, Failure::kDeviceError);
  EXPECT_EQ(task.result().message, "laser: timeout during the scan");
  ASSERT_FALSE(board->set().empty());
  EXPECT_FALSE(board->set().back()) << "the laser was left on";
  EXPECT_FALSE(task.result().scene.has_value());
}

// An arm whose relative moves come up short by a fraction (a loaded arm, a controller's
// rounding: through the twin's VAL II consoles a 50 mm lift came 3-4 mm short).
class ShortArm final : public device::Arm {
 public:
  ShortArm(std::unique_ptr<device::Arm> inner, double fraction)
      : inner_(std::move(inner)), fraction_(fraction) {}
  device::Status Read(device::ArmState* s) override { return inner_->Read(s); }
  device::Status MoveJoints(const device::Joint6& q) override { return inner_->MoveJoints(q); }
  device::Status MoveRelative(const Pose3& X_EEnew) override {
    Pose3 shorter = X_EEnew;
    shorter.translation() *= fraction_;
    return inner_->MoveRelative(shorter);
  }
  device::Status SetSpeed(double f) override { return inner_->SetSpeed(f); }
  device::Status Stop() override { return inner_->Stop(); }

 private:
  std::unique_ptr<device::Arm> inner_;
  double fraction_;
};

// The box seen in the hand but short of the lift is raised by what it lacks. Here the lift's
// moves come 15% short and the LEDs' correction of the gripper is switched off: the box ends
// about 42 mm up, which the cameras see; raised once more it is lifted, by the truth too.
TEST(GraspTaskSim, ABoxSeenShortOfTheLiftIsRaisedByWhatItLacks) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  for (const int relifts : {0, 1}) {
    sim::SimRobot robot(scenario);
    device::RobotDevices dev = robot.TakeDevices();
    for (device::Side side : {device::Side::kLeft, device::Side::kRight}) {
      auto& arm = dev.arm[static_cast<int>(side)];
      arm = std::make_unique<ShortArm>(std::move(arm), 0.85);
    }
    TaskConfig config = testing::ConfigFor(scenario);
    config.max_lift_corrections = 0;
    config.max_box_relifts = relifts;
    GraspTask task(&dev, testing::SimRobotModel(), config);
    ASSERT_TRUE(task.Look() && task.Plan() && task.Approach() && task.Servo() && task.Close());
    const sim::World& w = robot.world();
    const sim::SimObject* target = nullptr;
    double best = 1e9;
    const Eigen::Vector3d c = task.result().scene->boxes[*task.result().target].X_WO.translation();
    for (const sim::SimObject& o : w.objects()) {
      const double d = (w.BodyPose(o.body).translation() - c).head<2>().norm();
      if (d < best) best = d, target = &o;
    }
    ASSERT_NE(target, nullptr);
    const double z0 = w.BodyPose(target->body).translation().z();
    const bool lifted = task.Lift();
    const double rise = w.BodyPose(target->body).translation().z() - z0;
    const TaskResult& r = task.result();
    std::printf("relifts %d: %s, true rise %.1f mm, cameras %.1f-%.1f mm, relifted %d\n", relifts,
                lifted ? "lifted" : std::string(ToString(r.failure)).c_str(), 1e3 * rise,
                r.box_rise ? 1e3 * r.box_rise->min_m : 0.0,
                r.box_rise ? 1e3 * r.box_rise->max_m : 0.0, r.box_relifts);
    if (relifts == 0) {
      EXPECT_LT(rise, 0.045);
      EXPECT_FALSE(lifted);
      EXPECT_EQ(r.failure, Failure::kGraspSlipped);
    } else {
      EXPECT_EQ(r.box_relifts, 1);
      EXPECT_GE(rise, 0.045);
      EXPECT_TRUE(lifted) << r.message;
    }
  }
}

}  // namespace
}  // namespace hgrasp::task
