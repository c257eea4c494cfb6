// A cut arm link during a move (issue 16's acceptance): the task reports device_error naming the
// arm, and the safe stop stops that arm within 0.5 s of the cut. The cut is of the controller's
// transmit wire (the host hears nothing, the controller still hears the host): Val2Arm's
// SafeStop types the ABORT blind to a silent controller. With both wires cut nothing can reach
// the controller; then the safe stop reports the arm's stop as failed (second case), and the
// next call after the cable is mended ABORTs first (Val2Arm's lost-link recovery).
// The arms' lines are simulated (SimLine at 9600 baud, one SimClock for both drivers and their
// emulators), so the cut falls at the same moment of the move every run and the half second is
// measured in simulated time, whatever the machine's load. The rest of the robot is the
// simulator's own devices.

#include <gtest/gtest.h>

#include <functional>
#include <memory>

#include "app/safe_stop.h"
#include "common/clock.h"
#include "common/paths.h"
#include "emulators/sim_line.h"
#include "emulators/val2_emulator.h"
#include "serial/faulty_link.h"
#include "sim/sim_devices.h"
#include "task/grasp_task.h"
#include "val2/val2_arm.h"

namespace hgrasp {
namespace {

using device::Side;
using device::Status;

struct ArmOnAWire {
  ArmOnAWire(Side side, SimClock& clock) : host(clock, drivers::MakeVal2Emulator(side), 9600) {
    auto faulty = std::make_unique<drivers::FaultyLink>(host.Open(), drivers::FaultPlan{}, clock);
    wire = faulty.get();
    auto val2 =
        std::make_unique<drivers::Val2Arm>(std::move(faulty), drivers::Val2Options{}, clock);
    driver = val2.get();
    arm = std::move(val2);
  }
  drivers::Val2Emulator& Emulator(drivers::DeviceEmulator& d) {
    return dynamic_cast<drivers::Val2Emulator&>(d);
  }
  bool Moved() {
    return host.With([&](drivers::DeviceEmulator& d) {
      for (const auto& e : Emulator(d).executed()) {
        if (e.command.kind == drivers::val2::CommandKind::kMove) return true;
      }
      return false;
    });
  }
  // Emulator time of the first ABORT at or after t_s; negative when none.
  double AbortAfter(double t_s) {
    return host.With([&](drivers::DeviceEmulator& d) {
      for (const auto& e : Emulator(d).executed()) {
        if (e.t_s >= t_s && e.command.kind == drivers::val2::CommandKind::kAbort) return e.t_s;
      }
      return -1.0;
    });
  }
  bool Moving() {
    return host.With([&](drivers::DeviceEmulator& d) { return Emulator(d).model().moving(); });
  }

  drivers::SimLine host;
  drivers::FaultyLink* wire = nullptr;
  drivers::Val2Arm* driver = nullptr;
  std::unique_ptr<device::Arm> arm;
};

struct Outcome {
  task::TaskResult result;
  app::SafeStopReport safe;
  double t_cut = 0.0;   // emulator time of the cut
  double t_abort = -1;  // emulator time of the ABORT after it
  bool still_moving = true;
  std::string side;
};

// The default scene with both arms on emulators behind faulty wires; the planned arm's wire is
// cut (`both_ways`: both wires) once the arm is moving to the pre-grasp.
Outcome CutDuringTheApproach(bool both_ways) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  SimClock clock;
  ArmOnAWire left(Side::kLeft, clock), right(Side::kRight, clock);
  dev.arm[0] = std::move(left.arm);
  dev.arm[1] = std::move(right.arm);
  task::TaskConfig config;
  config.target_color = "yellow";
  task::GraspTask task(
      &dev,
      task::LoadRobotModel("calibration/sim/cameras.yaml", "calibration/sim/laser.yaml",
                           "calibration/sim/leds.yaml"),
      config);
  Outcome out;
  if (!task.Look() || !task.Plan()) {
    ADD_FAILURE() << task.result().message;
    return out;
  }
  ArmOnAWire& planned = task.result().plan->side == Side::kLeft ? left : right;
  out.side = std::string(device::ToString(task.result().plan->side));
  // Every 5 ms of the arms' time: once the planned arm has begun to move, the cut 200 ms later
  // (well into the move).
  std::function<void()> watch = [&] {
    if (!planned.Moved()) {
      clock.At(clock.Now() + Clock::FromSeconds(0.005), watch);
      return;
    }
    clock.At(clock.Now() + Clock::FromSeconds(0.2), [&] {
      out.t_cut = planned.host.Now();
      if (both_ways) {
        planned.wire->Cut(true);
      } else {
        planned.wire->CutFromDevice(true);
      }
    });
  };
  clock.At(clock.Now(), watch);
  EXPECT_FALSE(task.Approach());
  out.safe = app::LeaveSafe(dev);  // as the composition root does at once
  out.result = task.result();
  out.t_abort = planned.AbortAfter(out.t_cut);
  out.still_moving = planned.Moving();
  return out;
}

TEST(CutArmLink, TheArmIsNamedAndStoppedWithinHalfASecond) {
  const Outcome o = CutDuringTheApproach(/*both_ways=*/false);
  EXPECT_EQ(o.result.failure, task::Failure::kDeviceError);
  EXPECT_EQ(o.result.failed_device, "arm_" + o.side);
  EXPECT_EQ(o.result.message, "arm_" + o.side + ": timeout (read)");
  ASSERT_GE(o.t_abort, o.t_cut) << "the arm was not stopped";
  std::printf("cut at %.3f s, ABORT executed %.3f s after it\n", o.t_cut, o.t_abort - o.t_cut);
  EXPECT_LT(o.t_abort - o.t_cut, 0.5);
  EXPECT_FALSE(o.still_moving);
  // The stop went out but could not be confirmed: the report says so.
  EXPECT_FALSE(o.safe.ok());
  EXPECT_NE(o.safe.Failures().find("arm_" + o.side + " stop"), std::string::npos)
      << o.safe.Failures();
}

TEST(CutArmLink, ACableCutBothWaysIsReportedAndTheStopSaysItFailed) {
  const Outcome o = CutDuringTheApproach(/*both_ways=*/true);
  EXPECT_EQ(o.result.failure, task::Failure::kDeviceError);
  EXPECT_EQ(o.result.failed_device, "arm_" + o.side);
  EXPECT_LT(o.t_abort, 0.0);  // nothing reached the controller
  EXPECT_NE(o.safe.Failures().find("arm_" + o.side + " stop"), std::string::npos)
      << o.safe.Failures();
  const std::string other = o.side == "left" ? "arm_right" : "arm_left";
  EXPECT_EQ(o.safe.Json()[other]["stop"], "ok");
}

}  // namespace
}  // namespace hgrasp
