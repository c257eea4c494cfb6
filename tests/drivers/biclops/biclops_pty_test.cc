// BiclopsHead over the real transport (label realtime): a SerialPort on a pty, the emulated chip
// behind it in a thread of its own (EmulatorHost), in wall-clock time. What the protocol does,
// and how long it takes, is tested in simulated time (biclops_head_test.cc,
// biclops_fault_test.cc); this asserts only what the machine's load cannot change: the head is
// initialised and gets where it was sent, the chip executes each command once, and a vanished
// port is named kDisconnected and reopened.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>

#include "biclops/biclops_head.h"
#include "emulators/biclops_emulator.h"
#include "emulators/emulator.h"
#include "serial/serial_port.h"

namespace hgrasp::drivers {
namespace {

using device::Status;
namespace op = pmd::op;

// One encoder count of the default head, rad (12000 counts per turn).
constexpr double kCount = 2.0 * 3.14159265358979323846 / 12000.0;

BiclopsEmulator& Emu(DeviceEmulator& d) { return dynamic_cast<BiclopsEmulator&>(d); }

std::vector<PmdExecuted> Log(EmulatorHost& host) {
  return host.With([](DeviceEmulator& d) { return Emu(d).executed(); });
}

std::unique_ptr<SerialPort> OpenPort(const std::string& path) {
  std::string error;
  auto port = SerialPort::Open({path, 9600}, &error);
  EXPECT_TRUE(port) << error;
  return port;
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

// Reads until the head is at rest; a read may time out on a loaded machine (and is retried).
device::HeadState WaitStill(BiclopsHead& head) {
  device::HeadState s;
  for (int n = 0; n < 1000; ++n) {
    if (head.Read(&s) == Status::kOk && !s.moving) return s;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ADD_FAILURE() << "the head did not come to rest";
  return s;
}

TEST(BiclopsPty, InitialisesMovesAndReadsOverAPty) {
  EmulatorHost host(std::make_unique<BiclopsEmulator>());
  BiclopsHead head(OpenPort(host.port()));
  ASSERT_EQ(Retried([&] { return head.Initialize(); }), Status::kOk);
  const device::HeadJoints target{0.5, -0.3, 0.2};
  ASSERT_EQ(Retried([&] { return head.MoveTo(target); }), Status::kOk);
  const device::HeadState s = WaitStill(head);
  EXPECT_NEAR(s.q.pan, 0.5, kCount);
  EXPECT_NEAR(s.q.tilt, -0.3, kCount);
  EXPECT_NEAR(s.q.verge, 0.2, kCount);
  // The chip's log: the profile of each axis, then the three targets and their Updates, each
  // once.
  const std::array<std::int32_t, 3> counts = head.ToCounts(target);
  std::vector<PmdExecuted> expect;
  for (int a = 0; a < 3; ++a) {
    expect.push_back({0, a, op::kSetVelocity, head.velocity_register(a)});
    expect.push_back({0, a, op::kSetAcceleration, head.acceleration_register(a)});
  }
  for (int a = 0; a < 3; ++a) expect.push_back({0, a, op::kSetPosition, counts[a]});
  for (int a = 0; a < 3; ++a) expect.push_back({0, a, op::kUpdate, 0});
  EXPECT_EQ(Log(host), expect);
}

TEST(BiclopsPty, VanishedPortIsReportedAndTheDriverReconnects) {
  const std::string link =
      ::testing::TempDir() + "hgrasp_biclops_pty_link_" + std::to_string(::getpid());
  EmulatorHost host(std::make_unique<BiclopsEmulator>(), link);
  BiclopsHead head(OpenPort(link));
  ASSERT_EQ(Retried([&] { return head.MoveTo({0.3, 0.0, 0.0}); }), Status::kOk);
  host.Vanish();
  device::HeadState s;
  const Status gone = head.Read(&s);
  EXPECT_TRUE(gone == Status::kDisconnected || gone == Status::kTimeout) << ToString(gone);
  EXPECT_EQ(head.MoveTo({-0.3, 0.0, 0.0}), Status::kDisconnected);
  host.Reappear();
  // The driver reopens the same path on its own.
  Status back = Status::kDisconnected;
  for (int n = 0; n < 400 && back != Status::kOk; ++n) {
    back = head.MoveTo({-0.3, 0.0, 0.0});
    if (back != Status::kOk) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(back, Status::kOk);
  s = WaitStill(head);
  EXPECT_NEAR(s.q.pan, -0.3, 1e-3);
  // The chip kept its registers: after reading them again the driver sent only the new move.
  const std::vector<PmdExecuted> log = Log(host);
  ASSERT_EQ(log.size(), 10u);
  EXPECT_EQ(log[8].opcode, op::kSetPosition);
  EXPECT_EQ(log[9].opcode, op::kUpdate);
  EXPECT_GE(head.counters().disconnects, 1u);
}

}  // namespace
}  // namespace hgrasp::drivers
