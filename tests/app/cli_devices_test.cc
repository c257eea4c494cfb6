// The device configuration as the user meets it: `hgrasp emulate`, and devices that cannot be
// opened.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "biclops/biclops_head.h"
#include "cli_util.h"
#include "laser_board/laser_board.h"
#include "serial/pty.h"
#include "serial/serial_port.h"

namespace hgrasp {
namespace {

using device::Status;
using testing::RunHgrasp;

TEST(CliDevices, APortThatCannotBeOpenedExitsTwoNamingTheField) {
  const auto dir = std::filesystem::temp_directory_path() / "hgrasp_cli_devices";
  std::filesystem::create_directories(dir);
  const auto scenario = dir / "no_port.yaml";
  std::ofstream(scenario) << "name: no_port\n"
                             "devices:\n"
                             "  head: {driver: sim}\n"
                             "  arm_left: {driver: val2, port: /nonexistent/ttyS9, baud: 9600}\n";
  const auto out = dir / "out";
  std::filesystem::remove_all(out);
  const auto r = RunHgrasp("scan " + scenario.string() + " --out " + out.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("no_port.yaml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("devices.arm_left.port"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/ttyS9"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("No such file"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
}

// Starts `hgrasp emulate ARGS` and reads the port it prints.
struct Emulator {
  explicit Emulator(const std::string& args) {
    pipe = popen((std::string(HGRASP_BINARY) + " emulate " + args).c_str(), "r");
    char line[512] = {0};
    if (pipe != nullptr && std::fgets(line, sizeof(line), pipe) != nullptr) {
      port = line;
      while (!port.empty() && (port.back() == '\n' || port.back() == '\r')) port.pop_back();
    }
  }
  ~Emulator() {
    if (pipe != nullptr) pclose(pipe);  // waits for --seconds to run out
  }
  FILE* pipe = nullptr;
  std::string port;
};

TEST(CliDevices, EmulatePrintsAPortTheDriverTalksTo) {
  const std::string link = (std::filesystem::temp_directory_path() / "hgrasp_cli_head").string();
  Emulator emulator("biclops --link " + link + " --seconds 3");
  ASSERT_EQ(emulator.port, link);
  std::string error;
  auto port = drivers::SerialPort::Open({emulator.port, 9600}, &error);
  ASSERT_TRUE(port) << error;
  drivers::BiclopsHead head(std::move(port));
  device::HeadState state;
  EXPECT_EQ(head.Read(&state), Status::kOk);
  EXPECT_FALSE(state.moving);
}

TEST(CliDevices, EmulateWithoutALinkPrintsThePty) {
  Emulator emulator("laser_board --seconds 3");
  ASSERT_EQ(emulator.port.rfind("/dev/pts/", 0), 0u) << emulator.port;
  std::string error;
  auto port = drivers::SerialPort::Open({emulator.port, 115200}, &error);
  ASSERT_TRUE(port) << error;
  drivers::LaserBoard board(std::move(port));
  EXPECT_EQ(board.SetLaser(true), Status::kOk);
}

TEST(CliDevices, EmulateRejectsUnknownDevices) {
  const auto r = RunHgrasp("emulate toaster --seconds 1");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("toaster"), std::string::npos) << r.output;
  EXPECT_EQ(RunHgrasp("emulate val2 --side middle --seconds 1").status, 2);
}

// Issue 15: `--seconds` that is not a positive, finite time never ended (-1, 0, nan) or ended at
// once (inf). `timeout` turns a hang into a failure instead of a stuck test.
TEST(CliDevices, EmulateRefusesSecondsThatAreNoTime) {
  for (const char* seconds : {"-1", "0", "nan", "inf", "-inf", "1e300"}) {
    const auto r = RunHgrasp(std::string("emulate biclops --seconds ") + seconds, 20);
    EXPECT_EQ(r.status, 2) << seconds << ": " << r.output;
    EXPECT_NE(r.output.find("--seconds"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("expected a time in seconds"), std::string::npos) << r.output;
  }
}

TEST(CliDevices, EmulateStopsAfterSeconds) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = RunHgrasp("emulate sensorhand --seconds 0.3");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_GE(s, 0.3);
}

// Issue 15: `--link` replaced a user's file with its symlink and deleted it at exit; a link to a
// folder left a dangling `.new` beside it. Only a pty's link is ever replaced now.
TEST(CliDevices, EmulateLinkNeverReplacesAFileAFolderOrAnotherLink) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_link";
  fs::remove_all(dir);
  fs::create_directories(dir / "folder");
  std::ofstream(dir / "notes.txt") << "the user's notes\n";
  fs::create_symlink(dir / "notes.txt", dir / "other_link");
  for (const char* name : {"notes.txt", "folder", "other_link"}) {
    const auto r = RunHgrasp("emulate biclops --seconds 1 --link " + (dir / name).string());
    EXPECT_EQ(r.status, 2) << name << ": " << r.output;
    EXPECT_NE(r.output.find((dir / name).string()), std::string::npos) << r.output;
  }
  std::ifstream notes(dir / "notes.txt");
  std::string text;
  std::getline(notes, text);
  EXPECT_EQ(text, "the user's notes");
  EXPECT_TRUE(fs::is_directory(dir / "folder"));
  EXPECT_TRUE(fs::is_symlink(dir / "other_link"));
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  EXPECT_EQ(names.size(), 3u) << "something was left beside them";
  // A link a previous emulator left (to a pty that is gone) is replaced, and removed at exit.
  fs::create_symlink("/dev/pts/999999", dir / "stale");
  const auto r = RunHgrasp("emulate biclops --seconds 0.2 --link " + (dir / "stale").string());
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(fs::exists(fs::symlink_status(dir / "stale")));
  fs::remove_all(dir);
}

// Issue 15: with a head that never answers, `calibrate laser` still wrote a calibration (it
// read the head's angles and ignored the status). Now: exit 1 naming the head, nothing written.
TEST(CliDevices, CalibrationWithASilentHeadWritesNothing) {
  namespace fs = std::filesystem;
  drivers::Pty silent;  // a port nobody answers on
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_silent_head";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scenario = dir / "silent_head.yaml";
  std::ifstream target(std::string(HGRASP_ROOT_DIR) + "/scenarios/calibration_target.yaml");
  std::ofstream(scenario) << target.rdbuf() << "devices:\n  head: {driver: biclops, port: "
                          << silent.port() << "}\n";
  const fs::path out = dir / "laser.yaml";
  const auto r = RunHgrasp("calibrate laser " + scenario.string() + " --out " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("device_error: head: timeout"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

// Issue 16: a laser board that does not answer during the scan ended as no_target; now the scan
// ends as device_error naming the laser, and the report says so.
TEST(CliDevices, ASilentLaserBoardEndsTheScanAsADeviceError) {
  namespace fs = std::filesystem;
  drivers::Pty silent;  // a board nobody answers for
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_silent_laser";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scenario = dir / "silent_laser.yaml";
  std::ifstream base(std::string(HGRASP_ROOT_DIR) + "/scenarios/default.yaml");
  std::string text((std::istreambuf_iterator<char>(base)), std::istreambuf_iterator<char>());
  text.replace(text.find("devices: {}"), std::string("devices: {}").size(),
               "devices:\n  laser: {driver: laser_board, port: " + silent.port() + "}");
  std::ofstream(scenario) << text;
  for (const char* command : {"scan", "model"}) {
    const fs::path out = dir / command;
    const auto r = RunHgrasp(std::string(command) + " " + scenario.string() + " --out " +
                                 out.string(),
                             120);
    EXPECT_EQ(r.status, 1) << r.output;
    std::ifstream report(out / "report.json");
    const std::string json((std::istreambuf_iterator<char>(report)),
                           std::istreambuf_iterator<char>());
    EXPECT_NE(json.find("laser: timeout during the scan"), std::string::npos) << json;
    EXPECT_FALSE(fs::exists(out / "range.ply"));
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp
