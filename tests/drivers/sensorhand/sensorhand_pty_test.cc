// SensorHandHand over the real transport (label realtime): a SerialPort on a pty, the emulated
// hand behind it in a thread of its own (EmulatorHost), the driver's I/O loop in a thread on the
// wall clock. What the protocol does, and how close the estimate comes, is tested in simulated
// time (sensorhand_hand_test.cc); this asserts only what the machine's load cannot change: the
// stream starts, the closed loops land with the truth inside the driver's own bound (which a late
// echo widens), the hand executes each command the driver saw executed and none twice, and a
// vanished port is named and reopened.

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "emulators/emulator.h"
#include "emulators/sensorhand_emulator.h"
#include "sensorhand/sensorhand_hand.h"
#include "serial/serial_port.h"

namespace hgrasp::drivers {
namespace {

using device::HandState;
using device::Status;

std::unique_ptr<SensorHandEmulator> MakeHand(double object_width_m) {
  SensorHandMechanics m;
  m.object_width_m = object_width_m;
  return std::make_unique<SensorHandEmulator>(std::make_unique<KinematicSensorHand>(m));
}

std::unique_ptr<SerialPort> OpenPort(const std::string& path) {
  std::string error;
  auto port = SerialPort::Open(SensorHandHand::SerialConfigFor(path), &error);
  EXPECT_TRUE(port) << error;
  return port;
}

SensorHandEmulator& Emu(DeviceEmulator& d) { return dynamic_cast<SensorHandEmulator&>(d); }

// A call that failed on a loaded machine is retried through the driver's own API (which never
// sends a command twice).
template <class F>
Status Retried(F call) {
  Status s = Status::kTimeout;
  for (int n = 0; n < 20 && (s = call()) != Status::kOk && s != Status::kRejected; ++n) {
  }
  return s;
}

// The truth inside the driver's bound, and the fingers within `tol` of `target` beyond it.
void ExpectLanded(EmulatorHost& host, const SensorHandHand& hand, double target, double tol) {
  const SensorHandEstimate e = hand.estimate();
  const double truth = host.With([](DeviceEmulator& d) { return Emu(d).model().opening_m(); });
  EXPECT_LE(std::abs(e.opening_m - truth), e.uncertainty_m + 1e-9) << target;
  EXPECT_NEAR(truth, target, tol + e.uncertainty_m) << target;
}

// The hand executed exactly what the driver saw it execute, no setting twice in a row.
void ExpectNeverTwice(EmulatorHost& host, const SensorHandHand& hand) {
  const auto emu = host.With([](DeviceEmulator& d) { return Emu(d).speed_log(); });
  EXPECT_EQ(emu, hand.executed());
  EXPECT_TRUE(hand.unresolved().empty());
  for (std::size_t i = 1; i < emu.size(); ++i) EXPECT_FALSE(emu[i] == emu[i - 1]) << i;
}

TEST(SensorHandPty, OpensClosesAndReadsOverAPty) {
  EmulatorHost host(MakeHand(0.05));
  SensorHandHand hand(OpenPort(host.port()));
  HandState s;
  ASSERT_EQ(Retried([&] { return hand.Read(&s); }), Status::kOk);
  EXPECT_TRUE(host.With([](DeviceEmulator& d) { return Emu(d).streaming(); }));
  ASSERT_EQ(Retried([&] { return hand.Open(0.07); }), Status::kOk);
  ASSERT_TRUE(hand.WaitIdle(10.0));
  ExpectLanded(host, hand, 0.07, 0.001);
  ASSERT_EQ(Retried([&] { return hand.Close(30.0); }), Status::kOk);
  ASSERT_TRUE(hand.WaitIdle(10.0));
  const double force = host.With([](DeviceEmulator& d) { return Emu(d).model().grip_force_n(); });
  EXPECT_GT(force, 20.0);
  EXPECT_LE(force, 30.2);
  ASSERT_EQ(Retried([&] { return hand.Home(); }), Status::kOk);
  ASSERT_TRUE(hand.WaitIdle(10.0));
  // The open end stop fixes the estimate exactly, however late the echoes came.
  EXPECT_EQ(hand.estimate().opening_m, 0.10);
  EXPECT_EQ(host.With([](DeviceEmulator& d) { return Emu(d).model().opening_m(); }), 0.10);
  ExpectNeverTwice(host, hand);
}

TEST(SensorHandPty, VanishedPortIsNamedAndReopened) {
  const std::string link = ::testing::TempDir() + "hgrasp_sensorhand_pty_link";
  EmulatorHost host(MakeHand(0.0), link);
  SensorHandHand hand(OpenPort(link));
  HandState s;
  ASSERT_EQ(Retried([&] { return hand.Read(&s); }), Status::kOk);
  host.Vanish();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const Status open = hand.Open(0.02);
  EXPECT_TRUE(open == Status::kDisconnected || open == Status::kTimeout) << device::ToString(open);
  host.Reappear();
  Status r = Status::kTimeout;
  for (int n = 0; n < 100 && (r = hand.Read(&s)) != Status::kOk; ++n) {
  }
  ASSERT_EQ(r, Status::kOk);
  ASSERT_EQ(Retried([&] { return hand.Open(0.06); }), Status::kOk);
  ASSERT_TRUE(hand.WaitIdle(10.0));
  ExpectLanded(host, hand, 0.06, 0.001);
  EXPECT_TRUE(host.With([](DeviceEmulator& d) { return Emu(d).streaming(); }));
  ExpectNeverTwice(host, hand);
}

}  // namespace
}  // namespace hgrasp::drivers
