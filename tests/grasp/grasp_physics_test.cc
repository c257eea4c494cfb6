// Planned grasps executed in the simulator (ground truth read here only, to judge the outcome):
// seeded random scenes are scanned and modelled, the target's grasp planned, and the arm driven
// by joint targets to the pre-grasp and the grasp; the hand closes and the arm lifts by
// task.lift. The box must come up with the hand (issue 5: in 95% of 20 scenes).
//
// DISABLED: not met yet. Measured (seeds 1-20, about 5 min): 14 scenes planned (the other 6
// targets are wider than the open hand in both directions: the random scenes must draw a
// graspable target), 11 of those lifted; in 2 the box was knocked over (the joint-interpolated
// move from home to the pre-grasp is not checked for collisions), in 1 it slipped. Run with
// --gtest_also_run_disabled_tests.

#include <gtest/gtest.h>

#include <cstdio>

#include "common/paths.h"
#include "grasp/grasp_planner.h"
#include "model/scene_model.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "sim/random_scene.h"
#include "sim/sim_devices.h"

namespace hgrasp::grasp {
namespace {

// Lets simulated time run (a frame is 40 ms) until the arm and hand of `side` are still, or
// until `max_s` has passed.
void Settle(device::RobotDevices& dev, device::Side side, double max_s) {
  device::StereoFrame frame;
  for (double t = 0; t < max_s; t += 0.04) {
    device::ArmState a;
    device::HandState h;
    dev.ArmOf(side).Read(&a);
    dev.HandOf(side).Read(&h);
    if (!a.moving && !h.moving && t > 0.2) return;
    dev.cameras->Grab(&frame);
  }
}

struct Outcome {
  bool planned = false, lifted = false;
  double rise_m = 0;
};

Outcome GraspAndLift(const sim::Scenario& scenario) {
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  scan::Scanner scanner(
      robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf")),
      robot::LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml")),
      robot::LoadLaserCalibration(ResolveDataPath("calibration/sim/laser.yaml")));
  const model::SceneModel scene = model::ModelScene(scanner.Scan(dev, {}).range);
  const std::optional<int> target =
      model::ChooseByColour(scene.colours, scenario.task->target_color);
  Outcome out;
  if (!target) return out;
  const auto tree = robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  const auto left = robot::ArmKinematics::FromTree(tree, "left");
  const auto right = robot::ArmKinematics::FromTree(tree, "right");
  const std::optional<GraspPlan> plan = PlanGrasp(scene.boxes, *target, {&left, &right});
  if (!plan) return out;
  out.planned = true;
  const robot::ArmKinematics& arm = plan->side == device::Side::kLeft ? left : right;
  // The true object the target models: the one nearest its centre.
  const sim::SimObject* object = &robot.world().objects()[0];
  for (const sim::SimObject& o : robot.world().objects()) {
    if ((robot.world().BodyPose(o.body).translation() - scene.boxes[*target].X_WO.translation())
            .norm() < (robot.world().BodyPose(object->body).translation() -
                       scene.boxes[*target].X_WO.translation())
                          .norm()) {
      object = &o;
    }
  }
  const double z0 = robot.world().BodyPose(object->body).translation().z();
  // The lift: the grasp pose raised, in the grasp's arm configuration.
  Pose3 X_lift = plan->X_WE;
  X_lift.translation().z() += scenario.task->lift_m;
  device::Joint6 q_lift = plan->q;
  bool found = false;
  for (const robot::ArmIkSolution& s : arm.Inverse(X_lift)) {
    if (arm.WithinLimits(s.q) && (!found || (s.q - plan->q).norm() < (q_lift - plan->q).norm())) {
      q_lift = s.q, found = true;
    }
  }
  if (!found) return out;
  dev.HandOf(plan->side).Open(plan->opening_m);
  dev.ArmOf(plan->side).MoveJoints(plan->q_pre);
  Settle(dev, plan->side, 8.0);
  dev.ArmOf(plan->side).MoveJoints(plan->q);
  Settle(dev, plan->side, 4.0);
  dev.HandOf(plan->side).Close(40.0);
  Settle(dev, plan->side, 3.0);
  dev.ArmOf(plan->side).MoveJoints(q_lift);
  Settle(dev, plan->side, 4.0);
  out.rise_m = robot.world().BodyPose(object->body).translation().z() - z0;
  out.lifted = out.rise_m > 0.8 * scenario.task->lift_m;
  return out;
}

TEST(GraspPhysics, DISABLED_PlannedGraspsLiftTheBoxInRandomScenes) {
  int planned = 0, lifted = 0;
  const int scenes = 20;
  for (int seed = 1; seed <= scenes; ++seed) {
    const sim::Scenario scenario = sim::RandomBoxScene(seed);
    const Outcome o = GraspAndLift(scenario);
    planned += o.planned;
    lifted += o.lifted;
    std::printf("seed %2d (%s): %s, rise %.1f mm\n", seed, scenario.task->target_color.c_str(),
                o.planned ? (o.lifted ? "lifted" : "NOT lifted") : "no plan", 1e3 * o.rise_m);
  }
  std::printf("%d of %d scenes planned, %d lifted\n", planned, scenes, lifted);
  EXPECT_GE(lifted, 0.95 * scenes);
}

}  // namespace
}  // namespace hgrasp::grasp
