// The safe stop as a user meets it (issue 16, item 3; DESIGN.md rule 8): `hgrasp scan` stopped
// by SIGINT during the sweep and `hgrasp run` stopped by SIGTERM during an arm move, against the
// device emulators on ptys. The emulators' logs must show the laser off, its motor stopped, the
// LEDs off and both arms ABORTed after the signal, and the report must say `interrupted`.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <variant>

#include "emulators/biclops_emulator.h"
#include "emulators/emulator.h"
#include "emulators/laser_board_emulator.h"
#include "emulators/val2_emulator.h"

extern char** environ;

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
namespace lb = drivers::laser_board;
using device::Side;

// `hgrasp ARGS` in a child process, its output in `log`.
class Child {
 public:
  Child(const std::string& args, const fs::path& log) {
    const std::string cmd = "exec " + std::string(HGRASP_BINARY) + " " + args + " > " +
                            log.string() + " 2>&1";
    const char* argv[] = {"/bin/sh", "-c", cmd.c_str(), nullptr};
    if (posix_spawn(&pid_, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0) {
      pid_ = -1;
    }
  }
  ~Child() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  bool started() const { return pid_ > 0; }
  void Signal(int sig) { kill(pid_, sig); }
  // The exit status, or -1 when it has not exited within `timeout_s` (or died of a signal).
  int Wait(double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      int raw = 0;
      if (waitpid(pid_, &raw, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
};

bool WaitFor(const std::function<bool()>& done, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return done();
}

std::string ReadFile(const fs::path& p) {
  std::ifstream f(p);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

// The default scenario with `devices` as its devices block.
fs::path Scenario(const fs::path& dir, const std::string& devices) {
  std::string text = ReadFile(fs::path(HGRASP_ROOT_DIR) / "scenarios/default.yaml");
  text.replace(text.find("devices: {}"), std::string("devices: {}").size(), "devices:\n" + devices);
  const fs::path file = dir / "scenario.yaml";
  std::ofstream(file) << text;
  return file;
}

// The emulators of both arms and of the laser board, on ptys.
struct Emulators {
  Emulators()
      : arm_left(drivers::MakeVal2Emulator(Side::kLeft)),
        arm_right(drivers::MakeVal2Emulator(Side::kRight)),
        board(drivers::MakeLaserBoardEmulator()) {}

  std::vector<drivers::Val2Executed> Executed(drivers::EmulatorHost& arm) {
    return arm.With([](drivers::DeviceEmulator& d) {
      return dynamic_cast<drivers::Val2Emulator&>(d).executed();
    });
  }
  std::vector<drivers::LaserBoardLogEntry> BoardLog() {
    return board.With([](drivers::DeviceEmulator& d) {
      return dynamic_cast<drivers::LaserBoardEmulator&>(d).log();
    });
  }
  // Whether the arm executed an ABORT at or after emulator time t_s.
  bool Aborted(drivers::EmulatorHost& arm, double t_s) {
    for (const drivers::Val2Executed& e : Executed(arm)) {
      if (e.t_s >= t_s && e.command.kind == drivers::val2::CommandKind::kAbort) return true;
    }
    return false;
  }
  // Whether, after emulator time t_s, the board was told laser off, motor velocity 0 and both
  // LED sets off, and nothing turned them on or moved the motor again afterwards.
  bool BoardSafe(double t_s) {
    bool laser_off = false, motor_stopped = false;
    for (const drivers::LaserBoardLogEntry& e : BoardLog()) {
      if (e.t_s < t_s) continue;
      if (const auto* c = std::get_if<lb::SetLaser>(&e.command)) laser_off = !c->on;
      if (const auto* c = std::get_if<lb::MotorVelocity>(&e.command)) {
        motor_stopped = c->counts_s == 0;
      }
      if (std::holds_alternative<lb::MotorGoTo>(e.command)) motor_stopped = false;
    }
    return laser_off && motor_stopped && LedsOff(t_s);
  }
  // Whether both grippers' LEDs were last set to all off, at or after t_s.
  bool LedsOff(double t_s) {
    bool off[2] = {false, false};
    for (const drivers::LaserBoardLogEntry& e : BoardLog()) {
      if (e.t_s < t_s) continue;
      if (const auto* c = std::get_if<lb::SetLeds>(&e.command)) off[c->side & 1] = c->mask == 0;
    }
    return off[0] && off[1];
  }

  drivers::EmulatorHost arm_left, arm_right, board;
};

TEST(CliSafeStop, SigintDuringTheScanLeavesTheRobotSafeAndSaysInterrupted) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_sigint_scan";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Emulators emu;
  const fs::path scenario =
      Scenario(dir, "  arm_left: {driver: val2, port: " + emu.arm_left.port() +
                        "}\n  arm_right: {driver: val2, port: " + emu.arm_right.port() +
                        "}\n  laser: {driver: laser_board, port: " + emu.board.port() +
                        "}\n  leds: {driver: laser_board, port: " + emu.board.port() + "}\n");
  Child hgrasp("scan " + scenario.string() + " --out " + (dir / "out").string(), dir / "log");
  ASSERT_TRUE(hgrasp.started());
  // The sweep: the motor sent to the far end at the sweep's speed (slower than the slew).
  ASSERT_TRUE(WaitFor(
      [&] {
        for (const auto& e : emu.BoardLog()) {
          const auto* go = std::get_if<lb::MotorGoTo>(&e.command);
          if (go != nullptr && go->speed_counts_s < 9000) return true;
        }
        return false;
      },
      60))
      << ReadFile(dir / "log");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // into the sweep
  const double t_signal = emu.board.Now();
  hgrasp.Signal(SIGINT);
  EXPECT_EQ(hgrasp.Wait(10), 1) << ReadFile(dir / "log");
  EXPECT_TRUE(emu.BoardSafe(t_signal)) << ReadFile(dir / "log");
  EXPECT_TRUE(emu.Aborted(emu.arm_left, 0.0));
  EXPECT_TRUE(emu.Aborted(emu.arm_right, 0.0));
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir / "out/report.json"));
  EXPECT_EQ(report["failure"], "interrupted");
  EXPECT_EQ(report["failure_detail"], "SIGINT during the scan");
  EXPECT_EQ(report["safe_stop"]["laser"]["laser off"], "ok");
  EXPECT_EQ(report["safe_stop"]["laser"]["motor stop"], "ok");
  EXPECT_EQ(report["safe_stop"]["arm_right"]["stop"], "ok");
  EXPECT_FALSE(fs::exists(dir / "out/range.ply"));
  fs::remove_all(dir);
}

TEST(CliSafeStop, SigtermDuringAnArmMoveLeavesTheRobotSafeAndSaysInterrupted) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_sigterm_run";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Emulators emu;
  // The laser and the cameras simulated (the look must see the boxes); the arms and the LEDs
  // on their emulators.
  const fs::path scenario =
      Scenario(dir, "  arm_left: {driver: val2, port: " + emu.arm_left.port() +
                        "}\n  arm_right: {driver: val2, port: " + emu.arm_right.port() +
                        "}\n  leds: {driver: laser_board, port: " + emu.board.port() + "}\n");
  Child hgrasp("run " + scenario.string() + " --out " + (dir / "out").string(), dir / "log");
  ASSERT_TRUE(hgrasp.started());
  const auto moving = [&](drivers::EmulatorHost& arm) {
    for (const auto& e : emu.Executed(arm)) {
      if (e.command.kind == drivers::val2::CommandKind::kMove) return true;
    }
    return false;
  };
  ASSERT_TRUE(WaitFor([&] { return moving(emu.arm_left) || moving(emu.arm_right); }, 120))
      << ReadFile(dir / "log");
  const double t_signal = emu.arm_right.Now(), t_board = emu.board.Now();  // each host's clock
  hgrasp.Signal(SIGTERM);
  EXPECT_EQ(hgrasp.Wait(10), 1) << ReadFile(dir / "log");
  EXPECT_TRUE(emu.Aborted(emu.arm_left, 0.0));
  EXPECT_TRUE(emu.Aborted(emu.arm_right, t_signal));
  for (drivers::EmulatorHost* arm : {&emu.arm_left, &emu.arm_right}) {
    const bool still = arm->With([](drivers::DeviceEmulator& d) {
      return !dynamic_cast<drivers::Val2Emulator&>(d).model().moving();
    });
    EXPECT_TRUE(still);
  }
  EXPECT_TRUE(emu.LedsOff(t_board));
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir / "out/report.json"));
  EXPECT_EQ(report["failure"], "interrupted");
  EXPECT_EQ(report["failure_detail"], "SIGTERM during the approach");
  EXPECT_EQ(report["safe_stop"]["laser"]["laser off"], "ok");  // the simulated laser
  EXPECT_EQ(report["safe_stop"]["laser"]["motor stop"], "ok");
  EXPECT_EQ(report["safe_stop"]["leds"]["left off"], "ok");
  fs::remove_all(dir);
}

// The head's homing is a move too, and the one every start of a real robot makes: SIGTERM
// while the Biclops sweeps for its home sensor, with every serial device on its emulator.
TEST(CliSafeStop, SigtermDuringTheHeadsHomingLeavesEveryDeviceSafe) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_sigterm_homing";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Emulators emu;
  drivers::EmulatorHost head(drivers::MakeBiclopsEmulator(7));  // powered up away from home
  const fs::path scenario =
      Scenario(dir, "  arm_left: {driver: val2, port: " + emu.arm_left.port() +
                        "}\n  arm_right: {driver: val2, port: " + emu.arm_right.port() +
                        "}\n  head: {driver: biclops, port: " + head.port() +
                        "}\n  laser: {driver: laser_board, port: " + emu.board.port() +
                        "}\n  leds: {driver: laser_board, port: " + emu.board.port() + "}\n");
  const auto chip_moving = [&] {
    return head.With([](drivers::DeviceEmulator& d) {
      const auto& chip = dynamic_cast<drivers::BiclopsEmulator&>(d).chip();
      return chip.moving(0) || chip.moving(1) || chip.moving(2);
    });
  };
  Child hgrasp("run " + scenario.string() + " --out " + (dir / "out").string(), dir / "log");
  ASSERT_TRUE(hgrasp.started());
  ASSERT_TRUE(WaitFor(chip_moving, 60)) << ReadFile(dir / "log");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ASSERT_TRUE(chip_moving());  // still sweeping
  const double t_board = emu.board.Now();
  hgrasp.Signal(SIGTERM);
  EXPECT_EQ(hgrasp.Wait(10), 1) << ReadFile(dir / "log");
  EXPECT_FALSE(chip_moving()) << "the head was not stopped\n" << ReadFile(dir / "log");
  EXPECT_TRUE(emu.BoardSafe(t_board)) << ReadFile(dir / "log");
  EXPECT_TRUE(emu.Aborted(emu.arm_left, 0.0));
  EXPECT_TRUE(emu.Aborted(emu.arm_right, 0.0));
  const nlohmann::json report = nlohmann::json::parse(ReadFile(dir / "out/report.json"));
  EXPECT_EQ(report["failure"], "interrupted");
  EXPECT_EQ(report["failure_detail"], "SIGTERM during the homing");
  EXPECT_EQ(report["safe_stop"]["head"]["stop"], "ok");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp
