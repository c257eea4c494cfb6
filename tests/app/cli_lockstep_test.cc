// `hgrasp run --lockstep`: the whole grasp through the real serial drivers (VAL II, Biclops,
// SensorHand, laser board) and the twin's cameras, against the twin in simulated time in one
// process. Run twice: the same command logs byte for byte, the same twin record and the same
// report (wall-clock timings aside), whatever else the machine is doing; and by the twin's
// truth the gripper was where the plan put it when the hand closed, and the box rose; the
// report's truth block is the twin's.
// And the right arm's link cut both ways during the servo, at a twin time (--at): the run ends
// with device_error naming arm_right within 0.5 s of twin time, exit 1, the laser and the LEDs
// off; no ABORT can reach the controller, which finishes the motion it was running and stops.
// And the cameras stopped during the scan: device_error naming them within 1 s of twin time
// (0.580 s: the 0.5 s frame timeout from the scan's next grab).
// And scenes end as their simulated-device runs do (the issue's 30 random scenes with
// HGRASP_LOCKSTEP_SEEDS=A..B; the suite runs one).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "cli_util.h"
#include "run_compare.h"
#include "twin_process.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadJson;
using testing::ReadText;
using testing::Vec;
using testing::WithoutWallTimes;

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
  // The report's truth is the twin's (the run's truth rig on the twin's world, its stripe from
  // the twin's renders), as a simulated run's is the simulated robot's: the scan against the
  // true surfaces and stripe, each box found, and the target's rise as twin.json has it.
  ASSERT_TRUE(report.contains("truth"));
  const json& truth = report["truth"];
  EXPECT_LT(truth["range"].value("rms_to_surface_m", 1.0), 0.0015) << truth["range"].dump();
  EXPECT_GT(truth["range"].value("coverage", 0.0), 0.95) << truth["range"].dump();
  EXPECT_GT(truth["range"].value("truth_stripe_points", 0), 50000) << truth["range"].dump();
  ASSERT_EQ(truth["boxes"].size(), 2u);
  for (const json& b : truth["boxes"]) {
    EXPECT_TRUE(b.value("found", false)) << b.dump();
    EXPECT_LT(b.value("center_error_m", 1.0), 0.003) << b.dump();
    EXPECT_TRUE(b.value("color_ok", false)) << b.dump();
  }
  const std::string object = truth["run"].value("object", "");
  double twin_rise = -1.0;
  for (const json& b : twin["truth"]["boxes"]) {
    if (b["name"] == object) twin_rise = b["rise_m"].get<double>();
  }
  EXPECT_NEAR(truth["run"].value("object_rise_m", 0.0), twin_rise, 1e-4) << object;
  EXPECT_TRUE(twin.value("lockstep", false));
  EXPECT_EQ(twin["frames"].value("overruns", -1), 0);
  // Every serial device was driven through its wire.
  const json commands = json::parse(logs[0]);
  for (const char* key :
       {"arm_left", "arm_right", "hand_left", "hand_right", "head", "laser_board"}) {
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
  std::printf(
      "lockstep run: gripper %.2f mm from the plan at the close, box up %.1f mm; "
      "device time %.1f s, wall %.1f s and %.1f s\n",
      err_mm, 1e3 * rise, report.value("device_time_s", 0.0), reports[0].value("wall_time_s", 0.0),
      reports[1].value("wall_time_s", 0.0));
  fs::remove_all(dir);
}

// The twin times (since the twin started) at which the clean lockstep run of `scene` begins its
// look (the scan's first frame) and its servo: from its log ("run: look (device time T s)", the
// frames' clock: the twin's world time) less the twin's start (twin.json t0_s). -1 where absent.
struct MomentTimes {
  double look = -1.0, servo_start = -1.0;
};
MomentTimes CleanRunMoments(const std::string& scene, const fs::path& out) {
  const auto r =
      testing::RunHgrasp("run " + scene + " --lockstep --lean --out " + out.string(), 600);
  MomentTimes times;
  if (r.status != 0) return times;
  const double t0 = ReadJson(out / "twin.json").value("t0_s", 0.0);
  std::smatch m;
  if (std::regex_search(r.output, m, std::regex(R"(run: look \(device time ([0-9.]+) s\))"))) {
    times.look = std::stod(m[1].str()) - t0;
  }
  if (std::regex_search(r.output, m,
                        std::regex(R"(run: servo_start \(device time ([0-9.]+) s\))"))) {
    times.servo_start = std::stod(m[1].str()) - t0;
  }
  return times;
}

// A control command `what` at twin time `t_s` (--at) in two lockstep runs of `scene` (folders
// NAME0 and NAME1 in `dir`): each exits 1 and the two command logs are the same; the second
// run's report and twin record. Assertion failures are the caller's to stop on (HasFatalFailure).
struct ControlledRun {
  json report, twin;
};
ControlledRun RunTwiceWithControl(const std::string& scene, const fs::path& dir,
                                  const std::string& name, double t_s, const std::string& what) {
  char at[96];
  std::snprintf(at, sizeof at, "%.3f:%s", t_s, what.c_str());
  std::string logs[2];
  ControlledRun run;
  for (int i = 0; i < 2; ++i) {
    const fs::path out = dir / (name + std::to_string(i));
    const fs::path log = dir / (name + "_commands" + std::to_string(i) + ".json");
    const auto r = testing::RunHgrasp("run " + scene + " --lockstep --lean --out " + out.string() +
                                          " --at '" + at + "' --command-log " + log.string(),
                                      600);
    EXPECT_EQ(r.status, 1) << r.output;
    logs[i] = ReadText(log.string());
    run.report = ReadJson(out / "report.json");
    run.twin = ReadJson(out / "twin.json");
    EXPECT_TRUE(run.report.is_object()) << r.output;
    EXPECT_TRUE(run.twin.is_object()) << r.output;
    if (!run.report.is_object() || !run.twin.is_object()) return ControlledRun{};
  }
  EXPECT_EQ(logs[0], logs[1]);  // the same every run
  return run;
}

// The cameras' streams stopped 1 s into the scan (at a twin time, --at): device_error naming the
// cameras within 1 s of twin time (the grabber's frame timeout, 0.5 s, and the scan's pace) (the
// wall-clock run of the same, through GStreamer, is cli_twin_cut_test.cc), exit 1, the same every
// run.
void CamerasStoppedDuringTheScan(const std::string& scene, const fs::path& dir, double look_t) {
  const ControlledRun run =
      RunTwiceWithControl(scene, dir, "cameras", look_t + 1.0, "stop cameras");
  const json& report = run.report;
  const json& twin = run.twin;
  ASSERT_TRUE(report.is_object() && twin.is_object());
  EXPECT_EQ(report.value("failure", ""), "device_error") << report.dump(1);
  ASSERT_TRUE(report["failed_device"].is_string()) << report.dump(1);
  EXPECT_EQ(report["failed_device"].get<std::string>(), "cameras");
  ASSERT_EQ(twin["controls"].size(), 1u) << twin["controls"].dump();
  const double stop_twin = twin["controls"][0]["t_s"].get<double>();
  const double noticed = report["lockstep"]["task_end_twin_s"].get<double>() - stop_twin;
  // The grab that times out waits its whole frame timeout (0.5 s) from when the scan asked for
  // the frame, at most a frame period before the stop, or after it at the scan's pace (measured:
  // 0.580 s, every run). The budget is issue 17's: within 1 s.
  EXPECT_GE(noticed, 0.5 - 0.04);
  EXPECT_LE(noticed, 1.0);
  const json safe = report.value("safe_stop", json::object());
  EXPECT_EQ(safe.value("laser", json::object()).value("laser off", ""), "ok") << safe.dump();
  EXPECT_FALSE(twin["truth"]["laser_on"].get<bool>());
  std::printf("cameras stopped at twin %.3f s (look from %.3f s): device_error %.3f s after it\n",
              stop_twin, look_t, noticed);
}

// And the cameras stopped during the scan (CamerasStoppedDuringTheScan), on the same clean run's
// times.
TEST(CliLockstep, TheRightArmsLinkCutBothWaysDuringTheServoAndTheCamerasStoppedInTheScan) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_lockstep_cut";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = std::string(HGRASP_ROOT_DIR) + "/scenarios/default.yaml";
  const MomentTimes moments = CleanRunMoments(scene, dir / "clean");
  const double servo_t = moments.servo_start;
  ASSERT_GT(servo_t, 0.0) << "the clean run did not reach the servo";
  ASSERT_GT(moments.look, 0.0) << "the clean run did not look";
  CamerasStoppedDuringTheScan(scene, dir, moments.look);
  const ControlledRun run = RunTwiceWithControl(scene, dir, "cut", servo_t + 0.5, "cut arm_right");
  const json& report = run.report;
  const json& twin = run.twin;
  ASSERT_TRUE(report.is_object() && twin.is_object());
  EXPECT_EQ(report.value("failure", ""), "device_error") << report.dump(1);
  ASSERT_TRUE(report["failed_device"].is_string()) << report.dump(1);
  EXPECT_EQ(report["failed_device"].get<std::string>(), "arm_right");
  // Noticed within 0.5 s of twin time (the driver's 0.45 s silence budget).
  ASSERT_EQ(twin["controls"].size(), 1u) << twin["controls"].dump();
  const double cut_twin = twin["controls"][0]["t_s"].get<double>();
  const double noticed = report["lockstep"]["task_end_twin_s"].get<double>() - cut_twin;
  EXPECT_GE(noticed, 0.0);
  EXPECT_LE(noticed, 0.5);
  // Laser and LEDs off: as the safe stop reports them, and truly.
  const json safe = report.value("safe_stop", json::object());
  EXPECT_EQ(safe.value("laser", json::object()).value("laser off", ""), "ok") << safe.dump();
  EXPECT_EQ(safe.value("leds", json::object()).value("left off", ""), "ok") << safe.dump();
  EXPECT_EQ(safe.value("leds", json::object()).value("right off", ""), "ok") << safe.dump();
  EXPECT_FALSE(twin["truth"]["laser_on"].get<bool>());
  EXPECT_EQ(twin["truth"]["leds"]["left"].get<int>(), 0);
  EXPECT_EQ(twin["truth"]["leds"]["right"].get<int>(), 0);
  // No ABORT reaches a controller cut off both ways: it ran no command after the cut, finished
  // the motion in progress and stands (the twin's joints).
  const double cut_world = cut_twin + twin["t0_s"].get<double>();
  const json& times = twin["command_times_s"]["arm_right"];
  for (const json& t : times) EXPECT_LT(t.get<double>(), cut_world) << "a command after the cut";
  const double last_moving = twin["truth"]["arms"]["right"]["last_moving_t_s"].get<double>();
  std::printf(
      "arm link cut at twin %.3f s (servo from %.3f s): device_error %.3f s after it; "
      "the arm moved on %.3f s (finishing its move), then stood\n",
      cut_twin, servo_t, noticed, std::max(0.0, last_moving - cut_world));
  EXPECT_LT(last_moving - cut_world, 1.0);
  fs::remove_all(dir);
}

// A scene through the real drivers in lockstep against its simulated-device run: the same
// verdict; where the simulated run put the gripper within 5 mm / 2 deg of the plan, so does this
// one (by the twin's truth at the close); the boxes within the scan's own repeatability (1.5 mm
// centre, 2.5 mm edges, as cli_twin_test.cc). Returns whether it agreed; prints a line.
bool AgreesWithTheSimulatedRun(const std::string& scene, const fs::path& dir) {
  const std::string name = fs::path(scene).stem().string();
  SCOPED_TRACE(name);
  const fs::path sim_out = dir / (name + "_sim"), out = dir / (name + "_lockstep");
  const auto sim = testing::RunHgrasp("run " + scene + " --lean --out " + sim_out.string(), 600);
  const auto run =
      testing::RunHgrasp("run " + scene + " --lockstep --lean --out " + out.string(), 600);
  const json sim_report = ReadJson(sim_out / "report.json");
  const json report = ReadJson(out / "report.json");
  const json twin = ReadJson(out / "twin.json");
  if (!sim_report.is_object() || !report.is_object() || !twin.is_object()) {
    ADD_FAILURE() << sim.output << run.output;
    return false;
  }
  bool agrees = true;
  const json verdict = report.value("failure", json()),
             sim_verdict = sim_report.value("failure", json());
  EXPECT_EQ(verdict, sim_verdict) << run.output;
  agrees &= verdict == sim_verdict;
  const json at = sim_report.value("truth", json::object())
                      .value("run", json::object())
                      .value("grasp_reached", json::object());
  const bool sim_on_plan =
      at.value("gripper_to_plan_m", 1.0) < 0.005 && at.value("gripper_to_plan_deg", 99.0) < 2.0;
  double mm = -1.0, deg = -1.0;
  const bool gripped = testing::GripError(twin["truth"], report, &mm, &deg);
  if (sim_on_plan) {
    EXPECT_TRUE(gripped && mm < 5.0 && deg < 2.0) << mm << " mm, " << deg << " deg";
    agrees &= gripped && mm < 5.0 && deg < 2.0;
  }
  const testing::BoxAgreement boxes = testing::CompareBoxes(report, sim_report);
  EXPECT_LT(boxes.centre_m, 0.0015);
  EXPECT_LT(boxes.size_m, 0.0025);
  agrees &= boxes.centre_m < 0.0015 && boxes.size_m < 0.0025;
  const double wall = report.value("wall_time_s", 0.0), robot = report.value("device_time_s", 0.0);
  std::printf(
      "%s: %s (simulated: %s); grip %.2f mm %.2f deg (simulated %.2f mm); boxes within "
      "%.2f mm centre, %.2f mm edges; robot %.1f s in %.1f s wall (%.2fx real time)\n",
      name.c_str(), verdict.is_null() ? "ok" : verdict.get<std::string>().c_str(),
      sim_verdict.is_null() ? "ok" : sim_verdict.get<std::string>().c_str(), mm, deg,
      1e3 * at.value("gripper_to_plan_m", -0.001), 1e3 * boxes.centre_m, 1e3 * boxes.size_m, robot,
      wall, wall > 0.0 ? robot / wall : 0.0);
  std::fflush(stdout);
  return agrees;
}

TEST(CliLockstep, ScenesEndAsTheirSimulatedRunsDo) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_lockstep_scenes";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<std::string> scenes = {std::string(HGRASP_ROOT_DIR) +
                                     "/tests/data/twin/random_6.yaml"};
  if (const char* seeds = std::getenv("HGRASP_LOCKSTEP_SEEDS")) {
    scenes.clear();
    const auto r = testing::RunHgrasp("generate --family random_boxes --seeds " +
                                      std::string(seeds) + " --out " + (dir / "scenes").string());
    ASSERT_EQ(r.status, 0) << r.output;
    for (const auto& e : fs::directory_iterator(dir / "scenes"))
      scenes.push_back(e.path().string());
    std::sort(scenes.begin(), scenes.end());
  }
  int agreed = 0;
  for (const std::string& scene : scenes) agreed += AgreesWithTheSimulatedRun(scene, dir);
  std::printf("%d of %zu scenes end as their simulated runs do\n", agreed, scenes.size());
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp
