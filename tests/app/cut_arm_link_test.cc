// A cut arm link during a move (issue 16's acceptance): the task reports device_error naming the
// arm, and the safe stop stops that arm within 0.5 s of the cut. The cut is of the controller's
// transmit wire (the host hears nothing, the controller still hears the host): Val2Arm's
// SafeStop types the ABORT blind to a silent controller. With both wires cut nothing can reach
// the controller; then the safe stop reports the arm's stop as failed (second case), and the
// next call after the cable is mended ABORTs first (Val2Arm's lost-link recovery).

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>

#include "app/safe_stop.h"
#include "common/paths.h"
#include "emulators/emulator.h"
#include "emulators/val2_emulator.h"
#include "serial/faulty_link.h"
#include "serial/serial_port.h"
#include "sim/sim_devices.h"
#include "task/grasp_task.h"
#include "val2/val2_arm.h"

namespace hgrasp {
namespace {

using device::Side;
using device::Status;

struct ArmOnAWire {
  explicit ArmOnAWire(Side side) : host(drivers::MakeVal2Emulator(side)) {
    drivers::SerialConfig config;
    config.port = host.port();
    config.baud = 9600;
    std::string error;
    auto port = drivers::SerialPort::Open(config, &error);
    EXPECT_NE(port, nullptr) << error;
    auto faulty = std::make_unique<drivers::FaultyLink>(std::move(port), drivers::FaultPlan{});
    wire = faulty.get();
    auto val2 = std::make_unique<drivers::Val2Arm>(std::move(faulty));
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

  drivers::EmulatorHost host;
  drivers::FaultyLink* wire = nullptr;
  drivers::Val2Arm* driver = nullptr;
  std::unique_ptr<device::Arm> arm;
};

struct Outcome {
  task::TaskResult result;
  app::SafeStopReport safe;
  double t_cut = 0.0;    // emulator time of the cut
  double t_abort = -1;   // emulator time of the ABORT after it
  bool still_moving = true;
  std::string side;
};

// The default scene with both arms on emulators behind faulty wires; the planned arm's wire is
// cut (`both_ways`: both wires) once the arm is moving to the pre-grasp.
Outcome CutDuringTheApproach(bool both_ways) {
  const sim::Scenario scenario = sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  ArmOnAWire left(Side::kLeft), right(Side::kRight);
  dev.arm[0] = std::move(left.arm);
  dev.arm[1] = std::move(right.arm);
  task::TaskConfig config;
  config.target_color = "yellow";
  task::GraspTask task(&dev,
                       task::LoadRobotModel("calibration/sim/cameras.yaml",
                                            "calibration/sim/laser.yaml",
                                            "calibration/sim/leds.yaml"),
                       config);
  Outcome out;
  if (!task.Look() || !task.Plan()) {
    ADD_FAILURE() << task.result().message;
    return out;
  }
  ArmOnAWire& planned = task.result().plan->side == Side::kLeft ? left : right;
  out.side = std::string(device::ToString(task.result().plan->side));
  std::atomic<bool> done{false};
  std::thread cutter([&] {
    while (!done && !planned.Moved()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (done) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // well into the move
    out.t_cut = planned.host.Now();
    if (both_ways) {
      planned.wire->Cut(true);
    } else {
      planned.wire->CutFromDevice(true);
    }
  });
  EXPECT_FALSE(task.Approach());
  out.safe = app::LeaveSafe(dev);  // as the composition root does at once
  done = true;
  cutter.join();
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
