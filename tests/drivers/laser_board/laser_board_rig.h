#pragma once
// Test rigs: the laser board emulator on a simulated 115200-baud line in simulated time
// (SimBoardRig), or served on a real pty (BoardRig: EmulatorHost, the driver on a SerialPort);
// the driver optionally through a FaultyLink or a link that eats the board's replies.

#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "emulators/emulator.h"
#include "emulators/laser_board_emulator.h"
#include "emulators/sim_line.h"
#include "laser_board/board_devices.h"
#include "laser_board/laser_board.h"
#include "serial/faulty_link.h"
#include "serial/serial_port.h"
#include "tests/support/line_rig.h"

namespace hgrasp::drivers::testing {

/// Passes everything through, except that while `eat` is set every byte the board sends is
/// thrown away: the board executes commands whose replies the driver never sees.
class ReplyEater final : public ByteLink {
 public:
  explicit ReplyEater(std::unique_ptr<ByteLink> inner) : inner_(std::move(inner)) {}
  device::Status Write(std::span<const std::uint8_t> bytes) override {
    return inner_->Write(bytes);
  }
  device::Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override {
    const device::Status s = inner_->Read(buf, timeout_s, n);
    if (s == device::Status::kOk && eat) {
      *n = 0;
      return device::Status::kTimeout;
    }
    return s;
  }
  void Discard() override { inner_->Discard(); }
  std::atomic<bool> eat{false};

 private:
  std::unique_ptr<ByteLink> inner_;
};

/// The emulator on a pty under a stable link path, and a SerialPort at 115200 8N1 to it.
class BoardRig {
 public:
  explicit BoardRig(const std::string& name,
                    const LaserBoardEmulatorConfig& config = LaserBoardEmulatorConfig{})
      : host_(std::make_unique<LaserBoardEmulator>(config),
              ::testing::TempDir() + "hgrasp_laser_board_" + name) {}

  /// A serial port to the emulator (nullptr and a test failure when it cannot be opened).
  std::unique_ptr<SerialPort> OpenPort() {
    std::string error;
    SerialConfig config;
    config.port = host_.port();
    config.baud = laser_board::kBaud;
    auto port = SerialPort::Open(config, &error);
    EXPECT_TRUE(port) << error;
    return port;
  }

  EmulatorHost& host() { return host_; }

  /// Runs f(emulator) under the host's lock.
  template <class F>
  auto With(F&& f) {
    return host_.With([&](DeviceEmulator& d) { return f(dynamic_cast<LaserBoardEmulator&>(d)); });
  }
  std::vector<laser_board::Command> Executed() {
    return With([](LaserBoardEmulator& e) { return e.ExecutedCommands(); });
  }

 private:
  EmulatorHost host_;
};

/// The emulator on a simulated line (SimLine) at the board's baud rate, in simulated time.
class SimBoardRig : public hgrasp::testing::LineRig<LaserBoardEmulator> {
 public:
  explicit SimBoardRig(const LaserBoardEmulatorConfig& config = LaserBoardEmulatorConfig{})
      : LineRig(std::make_unique<LaserBoardEmulator>(config), laser_board::kBaud) {}

  std::vector<laser_board::Command> Executed() {
    return With([](LaserBoardEmulator& e) { return e.ExecutedCommands(); });
  }
};

}  // namespace hgrasp::drivers::testing
