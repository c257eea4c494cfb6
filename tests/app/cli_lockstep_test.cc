// `hgrasp run --lockstep`: the whole grasp through the real serial drivers (VAL II, Biclops,
// SensorHand, laser board) and the twin's cameras, against the twin in simulated time in one
// process. Run twice: the same command logs byte for byte, the same twin record and the same
// report (wall-clock timings aside), whatever else the machine is doing; and by the twin's
// truth the gripper was where the plan put it when the hand closed, and the box rose.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_util.h"
#include "twin_process.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadJson;
using testing::ReadText;

// `j` without the keys that measure the machine rather than the run.
json WithoutWallTimes(json j) {
  if (j.is_object()) {
    for (const char* k : {"timing_s", "wall_time_s", "wall_s", "mean_render_ms", "max_render_ms"}) {
      j.erase(k);
    }
    for (auto& [k, v] : j.items()) v = WithoutWallTimes(v);
  } else if (j.is_array()) {
    for (auto& v : j) v = WithoutWallTimes(v);
  }
  return j;
}

Eigen::Vector3d Vec(const json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

TEST(CliLockstep, TheWholeGraspThroughTheRealDriversTwiceTheSame) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_lockstep";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = std::string(HGRASP_ROOT_DIR) + "/scenarios/default.yaml";
  json reports[2], twins[2];
  std::string logs[2];
  for (int i = 0; i < 2; ++i) {
    const fs::path out = dir / ("run" + std::to_string(i));
    const fs::path log = dir / ("commands" + std::to_string(i) + ".json");
    const auto r = testing::RunHgrasp("run " + scene + " --lockstep --no-video --out " +
                                          out.string() + " --command-log " + log.string(),
                                      600);
    ASSERT_EQ(r.status, 0) << r.output;
    reports[i] = ReadJson(out / "report.json");
    twins[i] = ReadJson(out / "twin.json");
    logs[i] = ReadText(log.string());
    ASSERT_TRUE(reports[i].is_object()) << r.output;
    ASSERT_TRUE(twins[i].is_object()) << r.output;
  }
  const json& report = reports[0];
  const json& twin = twins[0];
  EXPECT_TRUE(report["result"].value("lifted", false));
  EXPECT_FALSE(report.contains("truth"));  // real drivers: the run knows no truth
  EXPECT_TRUE(twin.value("lockstep", false));
  EXPECT_EQ(twin["frames"].value("overruns", -1), 0);
  // Every serial device was driven through its wire.
  const json commands = json::parse(logs[0]);
  for (const char* key : {"arm_left", "arm_right", "hand_left", "hand_right", "head",
                          "laser_board"}) {
    ASSERT_TRUE(commands.contains(key)) << key;
  }
  EXPECT_FALSE(commands["arm_right"].empty());
  EXPECT_FALSE(commands["hand_right"].empty());
  EXPECT_FALSE(commands["head"].empty());
  EXPECT_FALSE(commands["laser_board"].empty());

  // One scenario, one run.
  EXPECT_EQ(logs[0], logs[1]);
  EXPECT_EQ(WithoutWallTimes(twins[0]), WithoutWallTimes(twins[1]));
  EXPECT_EQ(WithoutWallTimes(reports[0]), WithoutWallTimes(reports[1]));

  // By the twin's truth: the gripper at the plan when the hand began to close, the box up.
  const std::string side = report["grasp"]["arm"];
  json grip;
  for (const json& g : twin["truth"]["grips"]) {
    if (g["side"] == side) grip = g;
  }
  ASSERT_TRUE(grip.is_object()) << twin["truth"].dump();
  const double err_mm = 1e3 * (Vec(grip["p"]) - Vec(report["grasp"]["p_WE"])).norm();
  EXPECT_LT(err_mm, 5.0);
  double rise = 0.0;
  for (const json& b : twin["truth"]["boxes"]) rise = std::max(rise, b["rise_m"].get<double>());
  EXPECT_GT(rise, 0.045);
  std::printf("lockstep run: gripper %.2f mm from the plan at the close, box up %.1f mm; "
              "device time %.1f s, wall %.1f s and %.1f s\n",
              err_mm, 1e3 * rise, report.value("device_time_s", 0.0),
              reports[0].value("wall_time_s", 0.0), reports[1].value("wall_time_s", 0.0));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp
