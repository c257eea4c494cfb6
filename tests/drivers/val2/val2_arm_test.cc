// Val2Arm against the emulated VAL II controller on a simulated 9600-baud line (SimLine, in
// simulated time; over a real pty in val2_pty_test.cc):
// every command of the device::Arm seam, checked on the emulator's model and on the driver's
// readings; and the emulator's arm model on its own (speed limits, coordinated motion).

#include "val2/val2_arm.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <thread>

#include "emulators/sim_line.h"
#include "emulators/val2_emulator.h"
#include "tests/drivers/val2/val2_test_util.h"
#include "tests/support/line_rig.h"

namespace hgrasp::drivers {
namespace {

using device::Joint6;
using device::Status;

// An emulated controller on a simulated line and the driver on its other end.
struct Rig : hgrasp::testing::LineRig<Val2Emulator> {
  explicit Rig(std::unique_ptr<Val2Emulator> emulator = MakeVal2Emulator())
      : LineRig(std::move(emulator), 9600),
        arm(std::make_unique<Val2Arm>(Open(), Val2Options{}, clock)) {}
  std::vector<std::string> Executed() {
    return With([](Val2Emulator& e) {
      std::vector<std::string> lines;
      for (const Val2Executed& x : e.executed()) lines.push_back(x.line);
      return lines;
    });
  }
  // Reads until the driver reports the arm at rest (two equal readings).
  device::ArmState WaitStill(double timeout_s = 15.0) {
    device::ArmState s;
    const Clock::TimePoint end = clock.Now() + Clock::FromSeconds(timeout_s);
    while (clock.Now() < end) {
      EXPECT_EQ(arm->Read(&s), Status::kOk);
      if (!s.moving) return s;
      clock.SleepFor(0.02);
    }
    ADD_FAILURE() << "the arm did not come to rest";
    return s;
  }

  std::unique_ptr<Val2Arm> arm;
};

TEST(Val2Arm, ReadsTheJointsAtRest) {
  Rig rig;
  device::ArmState a, b;
  ASSERT_EQ(rig.arm->Read(&a), Status::kOk);
  ASSERT_EQ(rig.arm->Read(&b), Status::kOk);
  const Joint6 q = rig.With([](Val2Emulator& e) { return e.model().q(); });
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(b.q[k], q[k], DegToRad(0.0005));
  EXPECT_FALSE(b.moving);
  EXPECT_GT(b.t_s, a.t_s);
  EXPECT_EQ(b.qd.norm(), 0.0);
  EXPECT_TRUE(rig.Executed().empty());  // reading changes nothing
}

TEST(Val2Arm, MoveJointsReachesTheTarget) {
  Rig rig;
  const Joint6 target = Deg({20.5, -70.25, 40.125, 10, -30, -45.001});
  ASSERT_EQ(rig.arm->MoveJoints(target), Status::kOk);
  const device::ArmState s = rig.WaitStill();
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(s.q[k], target[k], DegToRad(0.0005)) << k;
  const Joint6 q = rig.With([](Val2Emulator& e) { return e.model().q(); });
  EXPECT_LT((q - target).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(rig.Executed(),
            std::vector<std::string>{val2::Encode(val2::MoveJointsCommand(ToDeg(target)))});
}

TEST(Val2Arm, ReadingsFollowTheMotion) {
  Rig rig;
  ASSERT_EQ(rig.arm->SetSpeed(0.2), Status::kOk);
  const Joint6 target = Deg({30, -60, 30, 0, -45, 0});
  ASSERT_EQ(rig.arm->MoveJoints(target), Status::kOk);
  device::ArmState s;
  bool saw_moving = false;
  for (int n = 0; n < 20; ++n) {
    ASSERT_EQ(rig.arm->Read(&s), Status::kOk);
    const Joint6 q = rig.With([](Val2Emulator& e) { return e.model().q(); });
    // The reading is not ahead of the model now (it moves on), within the printed 0.001 deg.
    EXPECT_LE(s.q[0], q[0] + DegToRad(0.0005) + 1e-12);
    if (s.moving && s.qd[0] > 0.0) saw_moving = true;
    rig.clock.SleepFor(0.01);
  }
  EXPECT_TRUE(saw_moving);
  rig.WaitStill();
}

TEST(Val2Arm, MoveRelativeInTheGripperFrame) {
  Rig rig;
  const Joint6 q0 = rig.With([](Val2Emulator& e) { return e.model().q(); });
  const Pose3 X_WE0 = rig.With([&](Val2Emulator& e) { return e.kinematics().Forward(q0); });
  Pose3 delta = Pose3::Identity();
  delta.translate(Eigen::Vector3d(0.012, -0.021, 0.0155));
  delta.rotate(Eigen::AngleAxisd(DegToRad(7.5), Eigen::Vector3d(1, 2, -1).normalized()));
  ASSERT_EQ(rig.arm->MoveRelative(delta), Status::kOk);
  rig.WaitStill();
  const Joint6 q1 = rig.With([](Val2Emulator& e) { return e.model().q(); });
  const Pose3 X_WE1 = rig.With([&](Val2Emulator& e) { return e.kinematics().Forward(q1); });
  const Pose3 want = X_WE0 * delta;
  EXPECT_LT((X_WE1.translation() - want.translation()).norm(), 2e-5);
  EXPECT_LT(Eigen::AngleAxisd(X_WE1.linear().transpose() * want.linear()).angle(), DegToRad(0.003));
  EXPECT_EQ(rig.Executed(), std::vector<std::string>{
                                val2::Encode(val2::MoveRelativeCommand(val2::PoseToTrans(delta)))});
}

TEST(Val2Arm, OutOfReachIsRejected) {
  Rig rig;
  Pose3 far = Pose3::Identity();
  far.translate(Eigen::Vector3d(0, 0, 2.0));
  EXPECT_EQ(rig.arm->MoveRelative(far), Status::kRejected);
  EXPECT_EQ(rig.arm->last_error(), "Position out of range");
  EXPECT_EQ(rig.arm->MoveJoints(Deg({170, -60, 30, 0, -45, 0})), Status::kRejected);
  EXPECT_EQ(rig.arm->SetSpeed(0.0), Status::kRejected);  // refused before sending
  EXPECT_EQ(rig.arm->SetSpeed(1.5), Status::kRejected);
  EXPECT_TRUE(rig.Executed().empty());
  const auto refused = rig.With([](Val2Emulator& e) { return e.refused(); });
  ASSERT_EQ(refused.size(), 2u);
  EXPECT_EQ(refused[0].second, "Position out of range");
  // The arm still works.
  EXPECT_EQ(rig.arm->MoveJoints(Deg({10, -60, 30, 0, -45, 0})), Status::kOk);
}

TEST(Val2Arm, SetSpeedScalesTheJointSpeeds) {
  Rig rig;
  ASSERT_EQ(rig.arm->SetSpeed(0.25), Status::kOk);
  EXPECT_EQ(rig.With([](Val2Emulator& e) { return e.speed_percent(); }), 25.0);
  ASSERT_EQ(rig.arm->MoveJoints(Deg({60, -60, 30, 0, -45, 0})), Status::kOk);
  // Joint 1 alone moves 60 deg: it cruises at 25 % of 120 deg/s.
  double peak = 0.0;
  for (int n = 0; n < 300; ++n) {
    peak = std::max(peak, rig.With([](Val2Emulator& e) { return std::abs(e.model().qd()[0]); }));
    rig.clock.SleepFor(0.005);
  }
  EXPECT_NEAR(RadToDeg(peak), 30.0, 0.5);
  EXPECT_EQ(rig.Executed()[0], "SPEED (25.00)");
}

TEST(Val2Arm, StopHoldsTheArmWhereItIs) {
  Rig rig;
  ASSERT_EQ(rig.arm->SetSpeed(0.1), Status::kOk);
  const Joint6 target = Deg({80, -60, 30, 0, -45, 0});
  ASSERT_EQ(rig.arm->MoveJoints(target), Status::kOk);
  rig.clock.SleepFor(0.3);
  ASSERT_EQ(rig.arm->Stop(), Status::kOk);
  const device::ArmState s = rig.WaitStill();
  EXPECT_GT(s.q[0], DegToRad(0.5));
  EXPECT_LT(s.q[0], DegToRad(20));
  const std::vector<std::string> log = rig.Executed();
  ASSERT_EQ(log.size(), 3u);
  EXPECT_EQ(log[2], "ABORT");
}

TEST(Val2Arm, ReadyGoesToVALsReadyPosition) {
  Rig rig;
  ASSERT_EQ(rig.arm->Ready(), Status::kOk);
  const device::ArmState s = rig.WaitStill();
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(RadToDeg(s.q[k]), Val2Emulator::kReadyDeg[k], 0.0005);
  EXPECT_EQ(rig.Executed(), std::vector<std::string>{"DO READY"});
}

TEST(Val2Arm, TheEmulatorAnswersAsTheProtocolSays) {
  // The emulator's answers byte for byte (PROTOCOL.md, "A session").
  auto emu = MakeVal2Emulator(device::Side::kLeft, {0, -90, 90, 0, 0, 0});
  std::vector<std::uint8_t> out;
  auto send = [&](const std::string& s) {
    out.clear();
    emu->Receive(
        std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()),
        0.0, &out);
    return std::string(out.begin(), out.end());
  };
  EXPECT_EQ(send("SPEED (50.00)\r"), "SPEED (50.00)\r\n.");
  EXPECT_EQ(send("SPEED 0\r"), "SPEED 0\r\n*Illegal value*\r\n.");
  EXPECT_EQ(send("FOO\r"), "FOO\r\n*Unknown command*\r\n.");
  EXPECT_EQ(send("\r"), "\r\n.");
  EXPECT_EQ(send("AB\x15"), "AB^U\r\n.");
  const std::string where = send("WHERE\r");
  EXPECT_EQ(where.substr(0, 7), "WHERE\r\n");
  EXPECT_EQ(where.back(), '.');
  EXPECT_NE(where.find("     0.000   -90.000    90.000     0.000     0.000     0.000\r\n"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// The arm model alone.

TEST(Val2ArmModel, JointsArriveTogetherWithinTheirLimits) {
  std::array<AxisLimits, 6> lim;
  const double v[6] = {2.09, 2.09, 2.88, 10.0, 7.5, 7.0};
  for (int k = 0; k < 6; ++k) lim[k] = {-5, 5, v[k], 4 * v[k]};
  TrapezoidArmModel m(lim, Joint6::Zero());
  Joint6 target;
  target << 1.0, -0.5, 0.25, 3.0, -2.0, 0.1;
  m.MoveJoints(target, 0.5);
  double t = 0.0;
  while (m.moving() && t < 20.0) {
    m.Advance(0.002);
    t += 0.002;
    const Joint6 q = m.q(), qd = m.qd();
    // Progress is the same fraction of the way for every joint.
    const double s0 = q[0] / target[0];
    for (int k = 0; k < 6; ++k) {
      EXPECT_NEAR(q[k] / target[k], s0, 2e-3) << "joint " << k << " at t " << t;
      EXPECT_LE(std::abs(qd[k]), 0.5 * v[k] + 1e-9);
    }
  }
  EXPECT_LT((m.q() - target).norm(), 1e-12);
  // Joint 1 (1 rad at 1.045 rad/s) limits the motion: about 1 s plus the ramps.
  EXPECT_GT(t, 0.9);
  EXPECT_LT(t, 1.6);
}

TEST(Val2ArmModel, ANewTargetReplacesTheMotion) {
  std::array<AxisLimits, 6> lim;
  for (int k = 0; k < 6; ++k) lim[k] = {-5, 5, 2.0, 8.0};
  TrapezoidArmModel m(lim, Joint6::Zero());
  Joint6 a = Joint6::Constant(1.0), b = Joint6::Constant(-0.5);
  m.MoveJoints(a, 1.0);
  for (int n = 0; n < 100; ++n) m.Advance(0.002);
  m.MoveJoints(b, 1.0);
  for (int n = 0; n < 5000 && m.moving(); ++n) m.Advance(0.002);
  EXPECT_LT((m.q() - b).norm(), 1e-12);
}

}  // namespace
}  // namespace hgrasp::drivers
