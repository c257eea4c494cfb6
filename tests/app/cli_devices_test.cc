// The device configuration as the user meets it: `hgrasp emulate`, and devices that cannot be
// opened.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "biclops/biclops_head.h"
#include "cli_util.h"
#include "laser_board/laser_board.h"
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

}  // namespace
}  // namespace hgrasp
