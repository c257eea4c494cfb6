// `hgrasp model` and `hgrasp plan` as a user runs them: the default scenario gives both boxes,
// the yellow one as the target, with every output DESIGN.md names, and a grasp of it; a target the
// robot cannot see exits 1 naming it; bad input exits 2 and writes nothing.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "tests/app/cli_util.h"

namespace {

using hgrasp::testing::RunHgrasp;
namespace fs = std::filesystem;

fs::path FreshOutDir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("hgrasp_cli_model_" + name);
  fs::remove_all(dir);
  return dir;
}

nlohmann::json ReadJson(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(CliModelTest, DefaultScenarioFindsBothBoxesAndTheYellowTarget) {
  const auto out = FreshOutDir("default");
  const auto r = RunHgrasp("model " + std::string(HGRASP_ROOT_DIR) +
                           "/scenarios/default.yaml --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* file : {"range.ply", "range.png", "segments.png", "models.png", "models.obj",
                           "models.mtl", "report.json"}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }
  const cv::Mat models = cv::imread((out / "models.png").string());
  EXPECT_EQ(models.cols, 640);
  EXPECT_EQ(models.rows, 480);
  const nlohmann::json report = ReadJson(out / "report.json");
  EXPECT_EQ(report["scenario"], "default");
  EXPECT_TRUE(report["ok"].get<bool>());
  EXPECT_TRUE(report["failure"].is_null());
  ASSERT_EQ(report["boxes"].size(), 2u);
  const int target = report["target"].get<int>();
  EXPECT_EQ(report["boxes"][target]["color_name"], "yellow");
  for (const auto& box : report["boxes"]) {
    EXPECT_EQ(box["center_W"].size(), 3u);
    EXPECT_EQ(box["R_WO"].size(), 3u);
    EXPECT_EQ(box["size"].size(), 3u);
    EXPECT_EQ(box["color_rgb"].size(), 3u);
    EXPECT_GT(box["points"].get<int>(), 100);
  }
  // The yellow box is 6 x 9 x 12 cm: its fitted height is within 4 mm.
  EXPECT_NEAR(report["boxes"][target]["size"][2].get<double>(), 0.12, 0.004);
  // A texture per visible face of each box, and the OBJ names them.
  int textures = 0;
  for (const auto& entry : fs::directory_iterator(out)) {
    textures += entry.path().filename().string().rfind("models_box", 0) == 0;
  }
  EXPECT_GE(textures, 4);
  for (const char* key : {"scan", "segment", "model", "total"}) {
    EXPECT_TRUE(report["timing_s"].contains(key)) << key;
  }
  EXPECT_EQ(report["truth"]["boxes"].size(), 2u);
}

TEST(CliPlanTest, DefaultScenarioPlansAGraspOfTheYellowBox) {
  const auto out = FreshOutDir("plan_default");
  const auto r = RunHgrasp("plan " + std::string(HGRASP_ROOT_DIR) +
                           "/scenarios/default.yaml --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "grasp.png"));
  const nlohmann::json report = ReadJson(out / "report.json");
  EXPECT_TRUE(report["ok"].get<bool>());
  const nlohmann::json& g = report["grasp"];
  ASSERT_TRUE(g.is_object());
  EXPECT_TRUE(g["arm"] == "left" || g["arm"] == "right");
  EXPECT_EQ(g["p_WE"].size(), 3u);
  EXPECT_EQ(g["R_WE"].size(), 3u);
  ASSERT_EQ(g["contacts_W"].size(), 2u);
  // The contacts on the yellow box's true faces within 3 mm, its 6 cm apart.
  EXPECT_EQ(report["truth"]["grasp"]["object"], "yellow_box");
  for (const auto& d : report["truth"]["grasp"]["contact_to_surface_m"]) {
    EXPECT_LT(d.get<double>(), 0.003);
  }
  Eigen::Vector3d c[2];
  for (int i = 0; i < 2; ++i) {
    for (int k = 0; k < 3; ++k) c[i][k] = g["contacts_W"][i][k].get<double>();
  }
  EXPECT_NEAR((c[1] - c[0]).norm(), 0.06, 0.004);
  EXPECT_TRUE(report["timing_s"].contains("plan"));
}

TEST(CliModelTest, TargetColourNotSeenExitsOneNamingIt) {
  const auto dir = FreshOutDir("no_target");
  fs::create_directories(dir);
  const fs::path scenario = dir / "red_wanted.yaml";
  std::ofstream(scenario) << "name: red_wanted\nobjects:\n  - {name: yellow_box, shape: box, "
                             "size: [0.06, 0.09, 0.12], position: [0.30, 0.0], yaw_deg: 20, "
                             "color: [0.95, 0.85, 0.10]}\ntask: {target: {color: red}}\n";
  const auto out = dir / "out";
  const auto r = RunHgrasp("model " + scenario.string() + " --out " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  const nlohmann::json report = ReadJson(out / "report.json");
  EXPECT_FALSE(report["ok"].get<bool>());
  EXPECT_EQ(report["failure"], "no_target");
  EXPECT_EQ(report["failure_detail"], "no red box found");
  EXPECT_TRUE(report["target"].is_null());
  EXPECT_EQ(report["boxes"].size(), 1u);
}

TEST(CliModelTest, BadScenarioExitsTwoAndWritesNothing) {
  const auto dir = FreshOutDir("bad");
  fs::create_directories(dir);
  const fs::path scenario = dir / "bad.yaml";
  std::ofstream(scenario) << "name: bad\nobjects:\n  - {name: b, shape: box, size: [0.06, -0.09, "
                             "0.12], position: [0.30, 0.0]}\n";
  const auto out = dir / "out";
  const auto r = RunHgrasp("model " + scenario.string() + " --out " + out.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("size"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(RunHgrasp("model " + scenario.string()).status, 2);  // no --out
}

}  // namespace
