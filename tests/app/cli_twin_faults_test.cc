// The whole grasp through noisy serial lines: `hgrasp twin` corrupts 1% of the bytes in each
// direction and drops every line out (both ways silent) for 200 ms at random, 0.2 times a second,
// while `hgrasp run` drives the VAL II consoles, the SensorHands, the Biclops and the laser
// board through their real drivers. The grasp must still succeed (the box lifted at least 45 mm
// by the twin's truth), and every device must have executed exactly what its driver says it had
// it execute: the driver's command log (hgrasp run --command-log) equal to the emulator's log of
// executed commands (twin.json "commands"), nothing lost, repeated or altered.
//
// "Equal" as drivers/serial/command_log.h defines it: the driver's log holds every command it
// sent that may have run, in order, each confirmed (the device executed it) or unconfirmed (it
// cannot know: a configuration Set* re-sent after a damaged reply, SafeStop's blind ABORT, the
// SensorHand's stream starts, sent again while its stream is silent). The device's log must be
// the driver's with each unconfirmed entry present once or not at all. A hand's log may end with
// the stream stop its driver's destructor sends after the run has written the logs.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "cli_util.h"
#include "sensorhand/sensorhand_codec.h"
#include "serial/command_log.h"
#include "twin_process.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using testing::ReadJson;

bool Unconfirmed(const json& e) { return e.is_object() && e.contains("unconfirmed"); }
const json& Command(const json& e) { return Unconfirmed(e) ? e["unconfirmed"] : e; }

// Whether `device` is `driver` with each unconfirmed entry of it kept once or dropped; if so,
// *ran counts the unconfirmed entries kept (as many as can be), else *why shows where the two
// part.
bool Matches(const json& driver, const json& device, int* ran, std::string* why) {
  const std::size_t n = driver.size(), m = device.size();
  // ok[i][j]: driver[i..] matches device[j..].
  std::vector<std::vector<char>> ok(n + 1, std::vector<char>(m + 1, 0));
  ok[n][m] = 1;
  for (std::size_t i = n; i-- > 0;) {
    for (std::size_t j = m + 1; j-- > 0;) {
      const bool same = j < m && Command(driver[i]) == device[j] && ok[i + 1][j + 1];
      ok[i][j] = same || (Unconfirmed(driver[i]) && ok[i + 1][j]);
    }
  }
  *ran = 0;
  if (ok[0][0]) {
    for (std::size_t i = 0, j = 0; i < n; ++i) {
      if (j < m && Command(driver[i]) == device[j] && ok[i + 1][j + 1]) {
        if (Unconfirmed(driver[i])) ++*ran;
        ++j;
      }
    }
    return true;
  }
  // Where they part: the furthest pair of places both can reach from their starts.
  std::vector<std::vector<char>> reach(n + 1, std::vector<char>(m + 1, 0));
  reach[0][0] = 1;
  std::size_t bi = 0, bj = 0;
  for (std::size_t i = 0; i <= n; ++i) {
    for (std::size_t j = 0; j <= m; ++j) {
      if (!reach[i][j]) continue;
      if (j > bj || (j == bj && i > bi)) bi = i, bj = j;
      if (i == n) continue;
      if (j < m && Command(driver[i]) == device[j]) reach[i + 1][j + 1] = 1;
      if (Unconfirmed(driver[i])) reach[i + 1][j] = 1;
    }
  }
  std::ostringstream s;
  s << "driver " << n << " entries, device " << m << "; they part at driver entry " << bi
    << ", device entry " << bj << "\n";
  using Place = std::tuple<const char*, const json*, std::size_t>;
  for (const auto& [name, log, at] : {Place{"driver", &driver, bi}, Place{"device", &device, bj}}) {
    s << "  " << name << ":";
    for (std::size_t k = at >= 4 ? at - 4 : 0; k < std::min(log->size(), at + 6); ++k) {
      s << (k == at ? "\n    > " : "\n      ") << k << " " << (*log)[k].dump();
    }
    s << "\n";
  }
  *why = s.str();
  return false;
}

// The dropouts are Poisson, each line working at least one dropout's length between two (the
// twin's --dropout-gap-s default): every outage is one 200 ms dropout. Without that gap two fell
// back to back now and then, a 0.4 s outage, which each driver reports as a lost link within
// 0.5 s by design (the cut-link acceptance), and the grasp survived 6 runs of 11.
//
// The twin draws its faults from the scenario's seed, so what the dropouts hit moves with the
// run's timing. 31 runs found three bugs: a VAL II DO APPRO logged as run that never ran (its
// whole answer lost), a line with a character more that passed the retype check ("...),00"),
// and a sweep whose missed stretches left a box 18 mm short, which the hand pushed over. After
// their fixes, 8 runs: every log equal, 3 lifted; the Biclops timed out homing or reading. Its
// resync zeros waited 20 ms each at 9600 baud, and one dropout could silence the chip for
// 0.37 s of its 0.4 s budget. With the shorter zero wait, 8 runs of 8 lifted (46.6-46.8 mm),
// every log equal, 68-79 s each: in the suite since. Its first CI run lost the lift's last
// step (rise 31 mm): a lost answer settled by one WHERE report a hair off the rest (a corrupted
// digit, an arm creeping under its load); the check now wants two reports on the way to the end.
TEST(CliTwinFaults, TheGraspSurvivesNoisyLinesAndEveryDeviceRanWhatItsDriverSent) {
  const auto t0 = std::chrono::steady_clock::now();
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_twin_faults";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = std::string(HGRASP_ROOT_DIR) + "/scenarios/default.yaml";
  testing::TwinProcess twin;  // stopped by its destructor whatever happens here
  ASSERT_TRUE(twin.Start(scene, dir / "twin",
                         {"--corrupt", "0.01", "--dropouts", "0.2", "--dropout-s", "0.2"}, 90.0))
      << twin.Log();
  const fs::path out = dir / "run";
  const fs::path logs_path = out / "commands.json";
  const auto run =
      testing::RunHgrasp("run " + (twin.dir() / "scenario.yaml").string() + " --out " +
                             out.string() + " --lean --command-log " + logs_path.string(),
                         300);
  const json twin_report = twin.Stop();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const json report = ReadJson(out / "report.json");
  ASSERT_TRUE(report.is_object()) << run.output;
  ASSERT_TRUE(twin_report.is_object()) << twin.Log();

  // The grasp succeeded by the twin's truth; the run says lifted, or grasp_slipped where its
  // cameras cannot rule out a rise under 45 mm (through the wires the box ends 45-47 mm up, see
  // cli_twin_test.cc), never another failure.
  const json result = report.value("result", json::object());
  if (report.value("ok", false)) {
    EXPECT_EQ(run.status, 0) << run.output;
    EXPECT_TRUE(result.value("lifted", false)) << run.output;
  } else {
    EXPECT_EQ(report.value("failure", json()), "grasp_slipped")
        << report.value("failure_detail", json()).dump() << run.output;
  }
  double rise = -1.0;
  const json boxes = twin_report.value("truth", json::object()).value("boxes", json::array());
  for (const json& b : boxes) {
    if (b.value("name", "") == "yellow_box") rise = b.value("rise_m", -1.0);
  }
  EXPECT_GE(rise, 0.045) << boxes.dump();

  // Every line had faults: corrupted bytes on each, dropouts on at least half of them.
  const json lines = twin_report.value("lines", json::object());
  ASSERT_EQ(lines.size(), 6u) << lines.dump();
  int with_dropouts = 0;
  for (const auto& [key, line] : lines.items()) {
    const json& f = line["faults"];
    EXPECT_GT(f["corrupted"].get<std::uint64_t>(), 0u) << key << ": " << f.dump();
    if (f["dropouts"].get<std::uint64_t>() > 0) ++with_dropouts;
  }
  EXPECT_GE(2 * with_dropouts, static_cast<int>(lines.size())) << lines.dump();

  // Each device executed what its driver logged: nothing lost, repeated or altered.
  const json driver_logs = ReadJson(logs_path);
  ASSERT_TRUE(driver_logs.is_object()) << run.output;
  const json device_logs = twin_report.value("commands", json::object());
  for (const auto& [key, line] : lines.items()) {
    SCOPED_TRACE(key);
    ASSERT_TRUE(driver_logs.contains(key)) << driver_logs.dump();
    ASSERT_TRUE(device_logs.contains(key));
    json driver = driver_logs[key];
    if (key.rfind("hand_", 0) == 0) {
      // The stream stop of the driver's destructor, after the run wrote the logs.
      driver.push_back({{"unconfirmed", drivers::HexBytes(drivers::sensorhand::EncodeDumpStop())}});
    }
    int ran = 0;
    std::string why;
    EXPECT_TRUE(Matches(driver, device_logs[key], &ran, &why)) << why;
    const auto unconfirmed = std::count_if(driver.begin(), driver.end(), Unconfirmed);
    const json& f = line["faults"];
    std::printf(
        "%-11s %6llu bytes, %4llu corrupted, %5llu dropped in %2llu dropouts; commands: device "
        "%zu, driver %zu confirmed + %zu unconfirmed (%d of them ran)\n",
        key.c_str(), static_cast<unsigned long long>(f["bytes"].get<std::uint64_t>()),
        static_cast<unsigned long long>(f["corrupted"].get<std::uint64_t>()),
        static_cast<unsigned long long>(f["dropped"].get<std::uint64_t>()),
        static_cast<unsigned long long>(f["dropouts"].get<std::uint64_t>()),
        device_logs[key].size(), driver.size() - static_cast<std::size_t>(unconfirmed),
        static_cast<std::size_t>(unconfirmed), ran);
    for (const json& r : line.value("refused", json::array())) {
      std::printf("%-11s refused: %s (%s)\n", key.c_str(), r.value("line", "").c_str(),
                  r.value("error", "").c_str());
    }
  }
  std::printf("run: ok %d, lifted %d, rise %.1f mm; run wall %.1f s, test wall %.1f s\n",
              static_cast<int>(report.value("ok", false)),
              static_cast<int>(result.value("lifted", false)), 1e3 * rise,
              report.value("timing_s", json::object()).value("total", 0.0), wall_s);
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp
