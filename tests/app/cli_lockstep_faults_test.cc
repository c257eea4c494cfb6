// The whole grasp through noisy serial lines, in simulated time: `hgrasp run --lockstep` on the
// twin's robot (scenarios/twin_robot.yaml: every device on its real driver, the Biclops homing
// fast), the twin corrupting 1% of the bytes in each direction and dropping every line out (both
// ways silent) for 200 ms at random, 0.2 times a second, each line working at least one dropout's
// length between two (every outage one dropout long; two back to back would be a 0.4 s outage,
// which each driver reports as a lost link within 0.5 s by design). The grasp must succeed (the
// box lifted at least 45 mm by the twin's truth), every device must have executed exactly what
// its driver says it had it execute (command_log_match.h), and the run, being in simulated time,
// must repeat itself: the same fault seed twice gives the same command logs byte for byte and
// the same report and twin record, wall-clock timings aside.
//
// HGRASP_LOCKSTEP_FAULT_SEEDS=A..B runs those fault seeds once each instead, for a measurement
// (the 50 seeds), and prints a line per seed and the tally; HGRASP_LOCKSTEP_FAULT_RATE
// sets the dropouts per second of such a measurement (0.2 by default).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_util.h"
#include "command_log_match.h"
#include "sensorhand/sensorhand_codec.h"
#include "serial/command_log.h"
#include "twin_process.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadJson;
using testing::WithoutWallTimes;

// The fault seed of the suite's run: the first of the seeds 1-50 measured for issue 36 (its
// closing notes). It was 2 while seed 1's run failed in the Biclops homing (fixed in b7e4d40).
constexpr int kSuiteSeed = 1;

struct FaultRun {
  int status = -1;
  std::string output;
  json report, twin, driver_logs;
  std::string logs_text;
};

FaultRun RunWithFaults(const fs::path& dir, int seed, const std::string& dropouts = "0.2") {
  const std::string scene = std::string(HGRASP_ROOT_DIR) + "/scenarios/twin_robot.yaml";
  const std::string name = std::to_string(seed) + (dropouts == "0.2" ? "" : "_at_" + dropouts);
  const fs::path out = dir / ("seed" + name);
  fs::remove_all(out);
  const fs::path logs = dir / ("commands" + name + ".json");
  const auto r = testing::RunHgrasp("run " + scene + " --lockstep --lean --out " + out.string() +
                                        " --corrupt 0.01 --dropouts " + dropouts +
                                        " --dropout-s 0.2 --fault-seed " + std::to_string(seed) +
                                        " --command-log " + logs.string(),
                                    600);
  FaultRun f;
  f.status = r.status;
  f.output = r.output;
  f.report = ReadJson(out / "report.json");
  f.twin = ReadJson(out / "twin.json");
  f.driver_logs = ReadJson(logs);
  f.logs_text = testing::ReadText(logs.string());
  return f;
}

double Rise(const json& twin) {
  double rise = -1.0;
  for (const json& b : twin["truth"]["boxes"]) {
    if (b.value("name", "") == "yellow_box") rise = b.value("rise_m", -1.0);
  }
  return rise;
}

// Whether each device executed what its driver logged (else *why says where a log parts);
// *summary gets a line per serial line.
bool LogsMatch(const FaultRun& f, std::string* summary, std::string* why) {
  if (!f.twin.is_object() || !f.driver_logs.is_object()) {
    *why = "no twin.json or no command log";
    return false;
  }
  bool all = true;
  const json& device_logs = f.twin["commands"];
  for (const auto& [key, line] : f.twin["lines"].items()) {
    if (!f.driver_logs.contains(key)) {
      *why += key + ": no driver log\n";
      all = false;
      continue;
    }
    json driver = f.driver_logs[key];
    if (key.rfind("hand_", 0) == 0) {
      // The stream stop of the driver's destructor, after the run wrote the logs.
      driver.push_back({{"unconfirmed", drivers::HexBytes(drivers::sensorhand::EncodeDumpStop())}});
    }
    int ran = 0;
    std::string parted;
    if (!testing::Matches(driver, device_logs[key], &ran, &parted)) {
      *why += key + ": " + parted;
      all = false;
    }
    const json& fl = line["faults"];
    char text[200];
    std::snprintf(text, sizeof text,
                  "%-11s %6llu bytes, %4llu corrupted, %2llu dropouts; device %zu commands, "
                  "driver %zu (%d unconfirmed ran)\n",
                  key.c_str(), static_cast<unsigned long long>(fl["bytes"].get<std::uint64_t>()),
                  static_cast<unsigned long long>(fl["corrupted"].get<std::uint64_t>()),
                  static_cast<unsigned long long>(fl["dropouts"].get<std::uint64_t>()),
                  device_logs[key].size(), driver.size(), ran);
    *summary += text;
  }
  return all;
}

// A range of fault seeds, once each: the tally of the measurement.
void MeasureSeeds(const fs::path& dir, const std::string& range, const std::string& dropouts) {
  const std::size_t dots = range.find("..");
  const int first = std::atoi(range.c_str());
  const int last = dots == std::string::npos ? first : std::atoi(range.c_str() + dots + 2);
  int lifted = 0, matched = 0, runs = 0;
  for (int seed = first; seed <= last; ++seed) {
    const FaultRun f = RunWithFaults(dir, seed, dropouts);
    ++runs;
    const double rise = f.twin.is_object() ? Rise(f.twin) : -1.0;
    std::string summary, why;
    const bool logs_ok = LogsMatch(f, &summary, &why);
    EXPECT_TRUE(logs_ok) << "fault seed " << seed << ": " << why;
    lifted += rise >= 0.045;
    matched += logs_ok;
    std::printf("fault seed %d: exit %d, %s%s, box up %.1f mm, logs %s\n", seed, f.status,
                f.report.value("failure", json()).is_string()
                    ? f.report["failure"].get<std::string>().c_str()
                    : "ok",
                f.report.value("failure_detail", json()).is_string()
                    ? (" (" + f.report["failure_detail"].get<std::string>() + ")").c_str()
                    : "",
                1e3 * rise, logs_ok ? "equal" : "NOT EQUAL");
    std::fflush(stdout);
  }
  std::printf(
      "fault seeds %s at %s dropouts/s: %d runs, %d lifted by truth, %d with every log "
      "equal\n",
      range.c_str(), dropouts.c_str(), runs, lifted, matched);
}

TEST(CliLockstepFaults, TheGraspSurvivesNoisyLinesEveryDeviceRanWhatItsDriverSentTwiceTheSame) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_lockstep_faults";
  fs::create_directories(dir);
  if (const char* seeds = std::getenv("HGRASP_LOCKSTEP_FAULT_SEEDS")) {
    const char* rate = std::getenv("HGRASP_LOCKSTEP_FAULT_RATE");
    MeasureSeeds(dir, seeds, rate != nullptr ? rate : "0.2");
    return;
  }
  const FaultRun a = RunWithFaults(dir, kSuiteSeed);
  const FaultRun b = RunWithFaults(dir, kSuiteSeed);
  ASSERT_TRUE(a.report.is_object()) << a.output;
  ASSERT_TRUE(a.twin.is_object()) << a.output;
  ASSERT_TRUE(a.driver_logs.is_object()) << a.output;
  EXPECT_EQ(a.status, 0) << a.output;
  EXPECT_TRUE(a.report["result"].value("lifted", false)) << a.output;
  EXPECT_GE(Rise(a.twin), 0.045) << a.twin["truth"]["boxes"].dump();

  // Every line had faults: corrupted bytes on each, dropouts on at least half of them.
  const json& lines = a.twin["lines"];
  ASSERT_EQ(lines.size(), 6u) << lines.dump();
  int with_dropouts = 0;
  for (const auto& [key, line] : lines.items()) {
    if (line["faults"]["dropouts"].get<std::uint64_t>() > 0) ++with_dropouts;
  }
  EXPECT_GE(2 * with_dropouts, static_cast<int>(lines.size())) << lines.dump();
  std::string summary, why;
  EXPECT_TRUE(LogsMatch(a, &summary, &why)) << why;
  std::printf("%s", summary.c_str());

  // One fault seed, one run.
  EXPECT_EQ(a.logs_text, b.logs_text);
  EXPECT_EQ(WithoutWallTimes(a.report), WithoutWallTimes(b.report));
  EXPECT_EQ(WithoutWallTimes(a.twin), WithoutWallTimes(b.twin));
  std::printf("fault seed %d: box up %.1f mm; twin time %.1f s; run wall %.1f s and %.1f s\n",
              kSuiteSeed, 1e3 * Rise(a.twin), a.twin.value("twin_s", 0.0),
              a.report.value("wall_time_s", 0.0), b.report.value("wall_time_s", 0.0));
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp
