// Box models against the simulator's ground truth (issue 4's acceptance): seeded random scenes of
// 1-3 boxes (edges 4-15 cm, any yaw, anywhere in the workspace, camera noise up to 2 grey levels),
// each scanned by the simulated robot and modelled by the pipeline. Every box must be found with
// its centre within 3 mm, every edge within 4 mm, yaw within 2 deg and the right colour name.
// Also: one scan gives the same models bit for bit.

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "common/paths.h"
#include "model/scene_model.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "sim/box_truth.h"
#include "sim/random_scene.h"
#include "sim/sim_devices.h"
#include "tests/scan/sim_scan.h"

namespace hgrasp::model {
namespace {

scan::RangeImage ScanScene(const sim::Scenario& scenario) {
  sim::SimRobot robot(scenario);
  return scan::testing::ScanInSim(&robot);
}

class RandomSceneAccuracy : public ::testing::TestWithParam<int> {};

TEST_P(RandomSceneAccuracy, EveryBoxFoundWithinTolerance) {
  const sim::Scenario scenario = sim::RandomBoxScene(GetParam());
  const std::vector<std::string> colour_names = sim::RandomSceneColorNames(scenario);
  // The truth: the boxes as the scenario places them (they rest on the table where put).
  sim::SimRobot truth_robot(scenario);
  const scan::RangeImage range = ScanScene(scenario);
  const SceneModel scene = ModelScene(range);
  EXPECT_EQ(scene.boxes.size(), scenario.objects.size());
  EXPECT_EQ(scene.unfitted, 0);
  for (size_t i = 0; i < scenario.objects.size(); ++i) {
    const sim::SimObject& object = truth_robot.world().objects()[i];
    const Pose3 X_WO = truth_robot.world().BodyPose(object.body);
    int best = -1;
    double best_d = 0.03;  // a box more than 3 cm off is not this one
    for (size_t k = 0; k < scene.boxes.size(); ++k) {
      const double d = (scene.boxes[k].X_WO.translation() - X_WO.translation()).norm();
      if (d < best_d) best_d = d, best = static_cast<int>(k);
    }
    const sim::ObjectSpec& spec = scenario.objects[i];
    ASSERT_GE(best, 0) << "seed " << GetParam() << ": " << spec.name << " not found";
    const sim::BoxError e =
        sim::CompareBox(X_WO, spec.size_O, scene.boxes[best].X_WO, scene.boxes[best].size_O);
    const std::string_view name = scene.colours[best].name();
    std::printf(
        "seed %2d %-14s size %3.0f %3.0f %3.0f mm yaw %6.1f: centre %.2f mm, edges %.2f %.2f %.2f "
        "mm, yaw %.2f deg, colour %s, noise %.1f\n",
        GetParam(), spec.name.c_str(), 1e3 * spec.size_O.x(), 1e3 * spec.size_O.y(),
        1e3 * spec.size_O.z(), RadToDeg(spec.yaw), 1e3 * e.center_m, 1e3 * e.edge_m.x(),
        1e3 * e.edge_m.y(), 1e3 * e.edge_m.z(), RadToDeg(e.yaw_rad), std::string(name).c_str(),
        scenario.camera_noise);
    EXPECT_LT(e.center_m, 0.003) << spec.name;
    EXPECT_LT(e.max_edge_m, 0.004) << spec.name;
    EXPECT_LT(RadToDeg(e.yaw_rad), 2.0) << spec.name;
    EXPECT_EQ(name, colour_names[i]) << spec.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomSceneAccuracy, ::testing::Range(1, 21));

TEST(SceneModelDeterminism, SameScanSameBoxesBitForBit) {
  const scan::RangeImage range =
      ScanScene(sim::LoadScenario(ResolveDataPath("scenarios/default.yaml")));
  const SceneModel a = ModelScene(range), b = ModelScene(range);
  ASSERT_EQ(a.boxes.size(), b.boxes.size());
  ASSERT_FALSE(a.boxes.empty());
  EXPECT_EQ(a.segments.labels, b.segments.labels);
  for (size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_EQ(std::memcmp(a.boxes[i].X_WO.matrix().data(), b.boxes[i].X_WO.matrix().data(),
                          16 * sizeof(double)),
              0);
    EXPECT_EQ(std::memcmp(a.boxes[i].size_O.data(), b.boxes[i].size_O.data(), 3 * sizeof(double)),
              0);
    EXPECT_EQ(a.colours[i].histogram, b.colours[i].histogram);
    ASSERT_EQ(a.textures[i].size(), b.textures[i].size());
    for (size_t f = 0; f < a.textures[i].size(); ++f) {
      EXPECT_EQ(cv::norm(a.textures[i][f].image, b.textures[i][f].image, cv::NORM_INF), 0);
    }
  }
  // And a second scan of the same scenario and seed: the same range image, so the same boxes.
  const scan::RangeImage again =
      ScanScene(sim::LoadScenario(ResolveDataPath("scenarios/default.yaml")));
  const SceneModel c = ModelScene(again);
  ASSERT_EQ(c.boxes.size(), a.boxes.size());
  for (size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_TRUE(c.boxes[i].X_WO.matrix() == a.boxes[i].X_WO.matrix());
    EXPECT_TRUE(c.boxes[i].size_O == a.boxes[i].size_O);
  }
}

}  // namespace
}  // namespace hgrasp::model
