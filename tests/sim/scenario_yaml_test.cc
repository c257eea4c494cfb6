// ScenarioYaml: what `hgrasp generate` writes reads back to the same scenario.

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "common/paths.h"
#include "sim/random_scene.h"
#include "sim/scenario.h"

namespace hgrasp::sim {
namespace {

void ExpectSame(const Scenario& a, const Scenario& b) {
  constexpr double kAngle = 1e-12;  // rad: degrees in the file
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.camera_noise, b.camera_noise);
  EXPECT_EQ(a.camera_samples, b.camera_samples);
  EXPECT_EQ(a.ambient, b.ambient);
  EXPECT_EQ(a.wall_x, b.wall_x);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    const ObjectSpec &x = a.objects[i], &y = b.objects[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.shape, y.shape);
    EXPECT_EQ(x.size_O, y.size_O);
    EXPECT_EQ(x.position_W, y.position_W);
    EXPECT_NEAR(x.yaw, y.yaw, kAngle);
    EXPECT_EQ(x.color_rgb, y.color_rgb);
    EXPECT_EQ(x.mass, y.mass);
    EXPECT_EQ(x.specular, y.specular);
  }
  ASSERT_EQ(a.interference.size(), b.interference.size());
  for (std::size_t i = 0; i < a.interference.size(); ++i) {
    EXPECT_EQ(a.interference[i].origin_W, b.interference[i].origin_W);
    EXPECT_NEAR(a.interference[i].sweep_min, b.interference[i].sweep_min, kAngle);
    EXPECT_NEAR(a.interference[i].sweep_max, b.interference[i].sweep_max, kAngle);
    EXPECT_EQ(a.interference[i].period_s, b.interference[i].period_s);
  }
  ASSERT_EQ(a.task.has_value(), b.task.has_value());
  if (a.task) {
    EXPECT_EQ(a.task->target_color, b.task->target_color);
    EXPECT_EQ(a.task->target_name, b.task->target_name);
    EXPECT_EQ(a.task->lift_m, b.task->lift_m);
  }
  const RobotErrorsSpec &r = a.robot_errors, &q = b.robot_errors;
  EXPECT_EQ(r.enabled, q.enabled);
  EXPECT_EQ(r.arm_joint_zero_deg, q.arm_joint_zero_deg);
  EXPECT_EQ(r.arm_link_mm, q.arm_link_mm);
  EXPECT_EQ(r.arm_backlash_deg, q.arm_backlash_deg);
  EXPECT_EQ(r.arm_encoder_deg, q.arm_encoder_deg);
  EXPECT_EQ(r.arm_latency_ms, q.arm_latency_ms);
  EXPECT_EQ(r.head_encoder_deg, q.head_encoder_deg);
  EXPECT_EQ(r.head_latency_ms, q.head_latency_ms);
  EXPECT_EQ(r.head_mount_mm, q.head_mount_mm);
  EXPECT_EQ(r.head_mount_deg, q.head_mount_deg);
  EXPECT_EQ(r.camera_focal_pct, q.camera_focal_pct);
  ASSERT_EQ(a.boards.size(), b.boards.size());
  for (std::size_t i = 0; i < a.boards.size(); ++i) {
    const BoardSpec &x = a.boards[i], &y = b.boards[i];
    EXPECT_EQ(x.cols, y.cols);
    EXPECT_EQ(x.rows, y.rows);
    EXPECT_NEAR(x.square_m, y.square_m, 1e-15);  // mm in the file
    EXPECT_EQ(x.position_W, y.position_W);
    EXPECT_NEAR(x.yaw, y.yaw, kAngle);
    EXPECT_NEAR(x.tilt, y.tilt, kAngle);
  }
  EXPECT_TRUE(b.devices.entries.empty());
}

TEST(ScenarioYaml, RandomScenesReadBackTheSame) {
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    SCOPED_TRACE(seed);
    const Scenario s = RandomBoxScene(seed);
    ExpectSame(s, ParseScenario(ScenarioYaml(s), "generated.yaml"));
  }
}

TEST(ScenarioYaml, EveryShippedSimulatedScenarioReadsBackTheSame) {
  int n = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(ResolveDataPath("scenarios"))) {
    if (entry.path().extension() != ".yaml") continue;
    const Scenario s = LoadScenario(entry.path().string());
    if (!s.devices.entries.empty()) continue;
    SCOPED_TRACE(entry.path().string());
    ExpectSame(s, ParseScenario(ScenarioYaml(s), "generated.yaml"));
    ++n;
  }
  EXPECT_GE(n, 3);  // default, plane_wall, calibration_target at least
}

TEST(ScenarioYaml, ARealDeviceIsRefused) {
  const Scenario s = ParseScenario(
      "name: real\ndevices:\n  head: {driver: biclops, port: /dev/ttyS1}\n", "real.yaml");
  EXPECT_THROW(ScenarioYaml(s), std::invalid_argument);
}

}  // namespace
}  // namespace hgrasp::sim
