// The composition root's choice of devices: real drivers on their ports where the scenario says
// so (here the emulators), the simulated robot's devices elsewhere.

#include "app/devices.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <thread>

#include "biclops/biclops_head.h"
#include "common/error.h"
#include "emulators/biclops_emulator.h"
#include "emulators/emulator.h"
#include "emulators/laser_board_emulator.h"
#include "emulators/sensorhand_emulator.h"
#include "emulators/val2_emulator.h"
#include "laser_board/board_devices.h"
#include "sensorhand/sensorhand_hand.h"
#include "tests/support/fast_homing.h"
#include "val2/val2_arm.h"

namespace hgrasp::app {
namespace {

using device::Side;
using device::Status;
namespace fs = std::filesystem;

// This test runs the real drivers on ptys against emulator threads in wall-clock time (label
// realtime), so a loaded machine may starve an emulator past a driver's own silence limit. It
// asserts what load cannot change: each wait ends done with the exact result, or with the
// driver's named failure (kTimeout), never with a wrong value. The same protocol logic runs
// exactly in simulated time in tests/app/cli_lockstep_test.cc.
//
// Reads with `read` every 20 ms until `done` holds or a read fails; returns the last read's
// status. The hang guard (60 s) is far beyond any driver's silence limit: it ends a hung test,
// it is not a latency bound.
Status ReadUntil(const std::function<Status()>& read, const std::function<bool()>& done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  Status last = read();
  while (Ok(last) && !done() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    last = read();
  }
  if (Ok(last) && !done()) ADD_FAILURE() << "neither done nor failed within the 60 s hang guard";
  return last;
}

// Load may end a wait with the driver's timeout; anything else is a failure of the protocol.
void ExpectDoneOrTimedOut(Status s, const char* what) {
  if (s == Status::kTimeout) {
    std::cout << what << ": the driver timed out (the machine's load), named as such\n";
    return;
  }
  EXPECT_EQ(s, Status::kOk) << what;
}

// Homing sweeps faster than BiclopsDefault.cfg's (pan 50 deg/s at 10 deg/s^2), as a test can
double TrueCounts(drivers::EmulatorHost& host, int axis) {
  return host.With([axis](drivers::DeviceEmulator& d) {
    return dynamic_cast<drivers::BiclopsEmulator&>(d).chip().position_counts(axis);
  });
}

TEST(MakeDevices, RealDriversWhereTheScenarioNamesThemSimulatedElsewhere) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_devices_test";
  fs::create_directories(dir);
  drivers::EmulatorHost arm(drivers::MakeVal2Emulator(Side::kLeft), (dir / "arm_left").string());
  drivers::EmulatorHost head(drivers::MakeBiclopsEmulator(), (dir / "head").string());
  drivers::EmulatorHost hand(drivers::MakeSensorHandEmulator(), (dir / "hand_right").string());
  drivers::EmulatorHost board(drivers::MakeLaserBoardEmulator(), (dir / "board").string());
  const fs::path file = dir / "emulated.yaml";
  std::ofstream(file) << "name: emulated\n"
                         "devices:\n"
                         "  arm_left: {driver: val2, port: "
                      << arm.port()
                      << "}\n"
                         "  head: {driver: biclops, port: "
                      << head.port() << ", options: " << testing::kFastHoming
                      << "}\n"
                         "  hand_right: {driver: sensorhand, port: "
                      << hand.port()
                      << "}\n"
                         "  laser: {driver: laser_board, port: "
                      << board.port()
                      << "}\n"
                         "  leds: {driver: laser_board, port: "
                      << board.port()
                      << "}\n"
                         "  cameras: {driver: sim}\n";
  const sim::Scenario scenario = sim::LoadScenario(file.string());
  Robot robot = OpenRobot(scenario);
  EXPECT_EQ(robot.truth(), nullptr);  // not every device is the twin's
  ASSERT_NE(robot.twin, nullptr);     // but some are
  device::RobotDevices& dev = robot.devices;

  // Which backend each device got: the composition root's choice, which load cannot change.
  EXPECT_NE(dynamic_cast<drivers::Val2Arm*>(dev.arm[0].get()), nullptr);
  EXPECT_EQ(dynamic_cast<drivers::Val2Arm*>(dev.arm[1].get()), nullptr);
  EXPECT_EQ(dynamic_cast<drivers::SensorHandHand*>(dev.hand[0].get()), nullptr);
  EXPECT_NE(dynamic_cast<drivers::SensorHandHand*>(dev.hand[1].get()), nullptr);
  EXPECT_NE(dynamic_cast<drivers::BiclopsHead*>(dev.head.get()), nullptr);
  EXPECT_NE(dynamic_cast<drivers::BoardStripeLaser*>(dev.laser.get()), nullptr);
  EXPECT_NE(dynamic_cast<drivers::BoardLeds*>(dev.leds.get()), nullptr);
  ASSERT_NE(dev.cameras, nullptr);

  // The head powered up away from its home (relative encoders): the composition root homed it,
  // or its start failed with the head's timeout, named with what the driver said (once, beside
  // two busy loops, the homing ran past its wall-clock budget).
  auto* biclops = dynamic_cast<drivers::BiclopsHead*>(dev.head.get());
  ASSERT_NE(biclops, nullptr);
  if (robot.start_failure) {
    EXPECT_EQ(robot.start_failure->device, "head") << robot.start_failure->detail;
    ExpectDoneOrTimedOut(robot.start_failure->status, "the head's homing");
    EXPECT_FALSE(robot.start_failure->detail.empty());
    return;  // no homed head to move; the rest of the robot was left safe by OpenRobot
  }
  EXPECT_TRUE(biclops->homed());
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(TrueCounts(head, a), 0.0, 1.0) << "axis " << a;
  // The stock SensorHand (no finger position on its wire), holding nothing, was opened to its
  // end stop: the driver's estimate is exact there.
  auto* sensorhand = dynamic_cast<drivers::SensorHandHand*>(dev.hand[1].get());
  ASSERT_NE(sensorhand, nullptr);
  EXPECT_TRUE(sensorhand->estimate().referenced);
  const double true_opening = hand.With([](drivers::DeviceEmulator& d) {
    return dynamic_cast<drivers::SensorHandEmulator&>(d).model().opening_m();
  });
  EXPECT_NEAR(true_opening, 0.10, 1e-3);
  EXPECT_NEAR(sensorhand->estimate().opening_m, true_opening, 1e-3);

  // Each real device works through the seam.
  const device::HeadJoints target{0.2, -0.1, 0.05};
  ASSERT_EQ(dev.head->MoveTo(target), Status::kOk);
  device::HeadState hs;
  const Status head_read =
      ReadUntil([&] { return dev.head->Read(&hs); }, [&] { return !hs.moving; });
  ExpectDoneOrTimedOut(head_read, "the head's move");
  if (Ok(head_read)) {
    EXPECT_NEAR(hs.q.pan, target.pan, 1e-3);
    EXPECT_NEAR(hs.q.tilt, target.tilt, 1e-3);
    EXPECT_NEAR(hs.q.verge, target.verge, 1e-3);
    const std::array<std::int32_t, 3> counts = biclops->ToCounts(target);  // in the true frame
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(TrueCounts(head, a), counts[a], 1.0) << "axis " << a;
  }

  ASSERT_EQ(dev.laser->SetLaser(true), Status::kOk);
  ASSERT_EQ(dev.laser->MoveTo(300, 6000.0), Status::kOk);
  device::StripeLaserState ls;
  const Status laser_read =
      ReadUntil([&] { return dev.laser->Read(&ls); }, [&] { return !ls.moving; });
  ExpectDoneOrTimedOut(laser_read, "the laser's move");
  if (Ok(laser_read)) {
    EXPECT_EQ(ls.encoder_count, 300);
    EXPECT_TRUE(ls.laser_on);
  }
  EXPECT_EQ(dev.leds->Count(Side::kLeft), 8);
  const Status leds_set = dev.leds->Set(Side::kLeft, 0b101);
  ExpectDoneOrTimedOut(leds_set, "the LEDs");
  EXPECT_EQ(dev.leds->Set(Side::kLeft, 1u << 8), Status::kRejected);  // refused before the wire

  device::Hand& right_hand = dev.HandOf(Side::kRight);
  ASSERT_EQ(right_hand.Open(0.06), Status::kOk);
  device::HandState hand_state;
  const Status hand_read =
      ReadUntil([&] { return right_hand.Read(&hand_state); }, [&] { return !hand_state.moving; });
  ExpectDoneOrTimedOut(hand_read, "the hand's opening");
  if (Ok(hand_read)) EXPECT_NEAR(hand_state.opening_m, 0.06, 0.002);

  device::Arm& left_arm = dev.ArmOf(Side::kLeft);
  device::ArmState as;
  ASSERT_EQ(left_arm.Read(&as), Status::kOk);
  device::Joint6 q = as.q;
  q[0] += 0.1;
  q[5] -= 0.2;
  ASSERT_EQ(left_arm.MoveJoints(q), Status::kOk);
  const Status arm_read = ReadUntil([&] { return left_arm.Read(&as); }, [&] { return !as.moving; });
  ExpectDoneOrTimedOut(arm_read, "the arm's move");
  if (Ok(arm_read)) EXPECT_LT((as.q - q).cwiseAbs().maxCoeff(), 1e-4);  // VAL prints 0.001 deg
}

TEST(MakeDevices, APortThatCannotBeOpenedIsBadInputNamingTheField) {
  const fs::path file = fs::temp_directory_path() / "hgrasp_devices_no_port.yaml";
  std::ofstream(file)
      << "name: no_port\ndevices:\n  head: {driver: biclops, port: /nonexistent/tty}\n";
  const sim::Scenario scenario = sim::LoadScenario(file.string());
  try {
    OpenRobot(scenario);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file.string() + ":3");  // the head's entry
    EXPECT_EQ(e.field(), "devices.head.port");
    EXPECT_EQ(e.value(), "/nonexistent/tty");
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(sim::LoadScenario(std::string(HGRASP_TEST_DATA) + "/scenarios/good_minimal.yaml")
                  .devices.AllSimulated());
}

}  // namespace
}  // namespace hgrasp::app
