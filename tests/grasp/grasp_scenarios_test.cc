// The shipped scenarios end to end, scan to grasp plan, against the simulator's ground truth:
// every box is modelled, and every box the open hand can span (its narrower horizontal edge plus
// the clearance within the opening; the workspace is within reach, issue 2) gets a plan whose
// contacts lie on the box's true faces within 3 mm.

#include <gtest/gtest.h>

#include <cstdio>

#include "common/paths.h"
#include "grasp/grasp_planner.h"
#include "model/scene_model.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"
#include "tests/scan/sim_scan.h"

namespace hgrasp::grasp {
namespace {

class ShippedScenario : public ::testing::TestWithParam<const char*> {};

TEST_P(ShippedScenario, EveryBoxModelledAndEverySpannableBoxPlanned) {
  const sim::Scenario scenario =
      sim::LoadScenario(ResolveDataPath(std::string("scenarios/") + GetParam()));
  sim::SimRobot robot(scenario);
  const model::SceneModel scene = model::ModelScene(scan::testing::ScanInSim(&robot));
  const auto tree = robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  const auto left = robot::ArmKinematics::FromTree(tree, "left");
  const auto right = robot::ArmKinematics::FromTree(tree, "right");
  const GraspConfig config;
  for (const sim::SimObject& object : robot.world().objects()) {
    const Pose3 X_WO = robot.world().BodyPose(object.body);
    int box = -1;
    for (size_t k = 0; k < scene.boxes.size(); ++k) {
      if ((scene.boxes[k].X_WO.translation() - X_WO.translation()).norm() < 0.03) {
        box = static_cast<int>(k);
      }
    }
    ASSERT_GE(box, 0) << object.spec.name << " not modelled";
    const double narrow = std::min(object.spec.size_O.x(), object.spec.size_O.y());
    const bool spannable = narrow + 2 * config.clearance_m <= config.hand.max_opening_m;
    const std::optional<GraspPlan> plan = PlanGrasp(scene.boxes, box, {&left, &right}, config);
    std::printf("%s %s: %s", GetParam(), object.spec.name.c_str(),
                plan ? "planned" : (spannable ? "NOT planned" : "too wide, no plan"));
    if (plan) {
      for (const Eigen::Vector3d& c : plan->contacts_W) {
        const double d = sim::DistanceToBoxSurface(X_WO, object.spec.size_O, c);
        std::printf(", contact %.2f mm off", 1e3 * d);
        EXPECT_LT(d, 0.003) << object.spec.name;
      }
    }
    std::printf("\n");
    EXPECT_EQ(plan.has_value(), spannable) << object.spec.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenarios, ShippedScenario,
                         ::testing::Values("default.yaml", "two_boxes_interference.yaml",
                                           "plane_wall.yaml"));

}  // namespace
}  // namespace hgrasp::grasp
