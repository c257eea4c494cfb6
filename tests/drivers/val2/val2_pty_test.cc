// Val2Arm over the real transport (label realtime): a SerialPort on a pty, the emulated VAL II
// controller behind it in a thread of its own (EmulatorHost), in wall-clock time. What the
// protocol does is tested in simulated time (val2_arm_test.cc, val2_fault_test.cc); this asserts
// only what the machine's load cannot change: commands arrive once and unaltered, the arm gets
// where it was sent, a vanished port is named kDisconnected and the driver reopens it.

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "emulators/val2_emulator.h"
#include "serial/serial_port.h"
#include "tests/drivers/val2/val2_test_util.h"
#include "val2/val2_arm.h"

namespace hgrasp::drivers {
namespace {

using device::Joint6;
using device::Status;

std::vector<std::string> Executed(EmulatorHost& host) {
  return host.With([](DeviceEmulator& d) {
    std::vector<std::string> lines;
    for (const Val2Executed& x : dynamic_cast<Val2Emulator&>(d).executed()) lines.push_back(x.line);
    return lines;
  });
}

std::unique_ptr<SerialPort> OpenPort(const std::string& path) {
  std::string error;
  auto port = SerialPort::Open({path, 9600}, &error);
  EXPECT_TRUE(port) << error;
  return port;
}

// Reads until the arm is at rest; a read may time out on a loaded machine (and is retried).
device::ArmState WaitStill(Val2Arm& arm) {
  device::ArmState s;
  for (int n = 0; n < 400; ++n) {
    if (arm.Read(&s) == Status::kOk && !s.moving) return s;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ADD_FAILURE() << "the arm did not come to rest";
  return s;
}

// A call that failed on a loaded machine is retried through the driver's own API (which never
// executes a command twice).
template <class F>
Status Retried(F call) {
  Status s = Status::kTimeout;
  for (int n = 0; n < 20 && (s = call()) != Status::kOk && s != Status::kRejected; ++n) {
  }
  return s;
}

TEST(Val2Pty, MovesAndReadsOverAPty) {
  EmulatorHost host(MakeVal2Emulator());
  Val2Arm arm(OpenPort(host.port()));
  const Joint6 target = Deg({20.5, -70.25, 40.125, 10, -30, -45.001});
  ASSERT_EQ(Retried([&] { return arm.SetSpeed(0.5); }), Status::kOk);
  ASSERT_EQ(Retried([&] { return arm.MoveJoints(target); }), Status::kOk);
  const device::ArmState s = WaitStill(arm);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(s.q[k], target[k], DegToRad(0.0005)) << k;
  EXPECT_EQ(Executed(host),
            (std::vector<std::string>{"SPEED (50.00)",
                                      val2::Encode(val2::MoveJointsCommand(ToDeg(target)))}));
}

TEST(Val2Pty, PortVanishesAndTheDriverReopensIt) {
  const std::string link = ::testing::TempDir() + "hgrasp_val2_pty_link";
  EmulatorHost host(MakeVal2Emulator(), link);
  Val2Arm arm(OpenPort(link));
  const Joint6 a = Deg({5, -55, 25, 1, -44, 2}), b = Deg({-5, -65, 35, -1, -46, -2});
  device::ArmState s;
  ASSERT_EQ(Retried([&] { return arm.Read(&s); }), Status::kOk);
  ASSERT_EQ(Retried([&] { return arm.MoveJoints(a); }), Status::kOk);

  host.Vanish();
  EXPECT_EQ(arm.MoveJoints(b), Status::kDisconnected);
  EXPECT_TRUE(arm.link_lost());
  EXPECT_EQ(arm.Read(&s), Status::kDisconnected);

  host.Reappear();
  // The driver reopens the same path on its own; a Read first, as after any lost link.
  Status r = Status::kDisconnected;
  for (int n = 0; n < 400 && r != Status::kOk; ++n) {
    r = arm.Read(&s);
    if (r != Status::kOk) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(r, Status::kOk);
  EXPECT_EQ(Retried([&] { return arm.MoveJoints(b); }), Status::kOk);
  EXPECT_EQ(Executed(host), (std::vector<std::string>{val2::Encode(val2::MoveJointsCommand(ToDeg(a))),
                                                      "ABORT",
                                                      val2::Encode(val2::MoveJointsCommand(ToDeg(b)))}));
}

}  // namespace
}  // namespace hgrasp::drivers
