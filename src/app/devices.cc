#include "app/devices.h"

#include <spdlog/spdlog.h>

#include <functional>

#include "app/output_dir.h"
#include "biclops/biclops_head.h"
#include "camera/gst_stereo_camera.h"
#include "common/error.h"
#include "common/write_file.h"
#include "config/device_config.h"
#include "laser_board/board_devices.h"
#include "laser_board/laser_board.h"
#include "sensorhand/sensorhand_hand.h"
#include "serial/command_log.h"
#include "serial/serial_port.h"
#include "val2/val2_arm.h"

namespace hgrasp::app {
namespace {

using device::Side;
namespace cfg = drivers;

// Below this grip force a hand holds nothing (N): DESIGN.md's grips are 10-100 N.
constexpr double kHoldingForceN = 5.0;

device::RobotDevices MakeLockstepDevices(const sim::Scenario& s, Robot& robot);

// "FILE:LINE" of a device's entry, for errors found when opening it.
std::string Where(const sim::Scenario& s, const cfg::DeviceConfig& d) {
  return d.line > 0 ? s.path + ":" + std::to_string(d.line) : s.path;
}

// Opens a device's serial port; a port that cannot be opened is bad input (exit 2), named.
std::unique_ptr<drivers::ByteLink> OpenPort(const sim::Scenario& s, const std::string& key) {
  const cfg::DeviceConfig& d = *s.devices.Find(key);
  const drivers::SerialConfig& serial = *d.serial();
  std::string error;
  std::unique_ptr<drivers::SerialPort> port = drivers::SerialPort::Open(serial, &error);
  if (!port) {
    throw InputError(Where(s, d), "devices." + key + ".port", serial.port,
                     "a serial port that can be opened at " + std::to_string(serial.baud) + " " +
                         cfg::Framing(serial) + " (" + error + ")");
  }
  return port;
}

// A driver's command log: each entry as `encode` gives it, an unconfirmed one wrapped as
// {"unconfirmed": entry}.
template <class Command, class Encode>
nlohmann::json LogJson(const drivers::CommandLog<Command>& log, Encode encode) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& e : log.Snapshot()) {
    nlohmann::json j = encode(e.command);
    out.push_back(e.confirmed ? std::move(j) : nlohmann::json{{"unconfirmed", std::move(j)}});
  }
  return out;
}

}  // namespace

Robot::~Robot() {
  if (!left_safe_) LeaveSafe();
}

SafeStopReport Robot::LeaveSafe() {
  left_safe_ = true;
  SafeStopReport report = app::LeaveSafe(devices);
  if (!report.ok()) spdlog::error("safe stop: {}", report.Failures());
  return report;
}

std::string StartFailure::failure() const {
  return status == device::Status::kInterrupted ? "interrupted" : "device_error";
}

nlohmann::json StartFailure::Report(const sim::Scenario& scenario,
                                    const SafeStopReport& safe) const {
  return {{"scenario", scenario.name},
          {"seed", scenario.seed},
          {"ok", false},
          {"failure", failure()},
          {"failure_detail", detail},
          {"failed_device", status == device::Status::kInterrupted ? nlohmann::json(nullptr)
                                                                   : nlohmann::json(device)},
          {"safe_stop", safe.Json()}};
}

bool EndedAtStart(Robot& robot, const sim::Scenario& scenario, OutputDir* out,
                  std::string_view command) {
  if (!robot.start_failure) return false;
  const SafeStopReport safe = robot.LeaveSafe();
  const StartFailure& f = *robot.start_failure;
  if (out != nullptr) {
    WriteFileWhole(out->Path("report.json"), f.Report(scenario, safe).dump(2) + "\n");
    WriteTwinRecord(robot, *out);
    out->Commit();
  }
  spdlog::error("{}: {}: {}{}", command, f.failure(), f.detail,
                out != nullptr ? "; wrote " + out->dir() : std::string("; nothing written"));
  return true;
}

void WriteTwinRecord(const Robot& robot, OutputDir& out) {
  if (robot.lockstep) {
    WriteFileWhole(out.Path("twin.json"), robot.lockstep->Report().dump(1) + "\n");
  }
}

drivers::DevicesConfig LockstepDevices(const drivers::DevicesConfig& given) {
  drivers::DevicesConfig c;
  auto take = [&](const std::string& key, auto backend) {
    using B = decltype(backend);
    if (const B* b = given.Backend<B>(key)) backend = *b;
    c.entries[key] = cfg::DeviceConfig{backend, 0};
  };
  for (const char* key : {"arm_left", "arm_right"}) take(key, cfg::Val2Backend{});
  for (const char* key : {"hand_left", "hand_right"}) take(key, cfg::SensorHandBackend{});
  take("head", cfg::BiclopsBackend{});
  take("laser", cfg::LaserBoardBackend{});
  take("leds", cfg::LaserBoardBackend{});
  return c;
}

namespace {

// The twin of a lockstep run on its own SimClock (robot->clock), its frames for the lockstep
// camera (robot->frames), the wires' faults and the --at schedule as events of that clock.
// Returns the scenario whose devices the run opens: every device on its real driver.
sim::Scenario StartLockstepTwin(const sim::Scenario& given, const TwinWireOptions& wires,
                                Robot* robot) {
  const std::vector<ScheduledControl> schedule = CheckTwinWires(wires);
  sim::Scenario scenario = given;
  scenario.devices = LockstepDevices(given.devices);
  robot->clock = std::make_unique<SimClock>();
  robot->frames = std::make_shared<sim::LockstepFrames>();
  sim::TwinOptions options = TwinOptionsFor(wires, given);
  options.lockstep = robot->clock.get();
  // The twin's world is the scenario's, its devices all simulated (they are the twin's).
  sim::Scenario world = given;
  world.devices = {};
  robot->lockstep = std::make_unique<sim::Twin>(std::move(world), options,
                                                sim::LockstepFrames::SinkFor(robot->frames));
  sim::Twin* twin = robot->lockstep.get();
  const double t_start = twin->time();
  for (const ScheduledControl& c : schedule) {
    robot->clock->At(Clock::TimePoint(Clock::FromSeconds(t_start + c.t_s)), [twin, c, t_start] {
      const std::string err = twin->Control(c.command);
      spdlog::info("twin: t = {:.3f} s: {}{}{}", twin->time() - t_start, c.command,
                   err.empty() ? "" : ": ", err);
    });
  }
  return scenario;
}

}  // namespace

const TwinWireOptions* CleanLockstepWires(bool lockstep) {
  static const TwinWireOptions kClean;
  return lockstep ? &kClean : nullptr;
}

Robot OpenRobot(const sim::Scenario& given, const StopRequest* stop,
                const TwinWireOptions* lockstep) {
  Robot robot;
  sim::Scenario lockstep_scenario;
  if (lockstep != nullptr) lockstep_scenario = StartLockstepTwin(given, *lockstep, &robot);
  const sim::Scenario& scenario = lockstep != nullptr ? lockstep_scenario : given;
  robot.all_simulated = scenario.devices.AllSimulated();
  if (scenario.devices.AnySimulated()) robot.twin = std::make_unique<sim::SimRobot>(scenario);
  robot.devices = lockstep != nullptr ? MakeLockstepDevices(scenario, robot)
                                      : MakeDevices(scenario, robot.twin.get());
  if (robot.all_simulated && robot.twin) {
    robot.truth_world = TruthWorld{&robot.twin->world(), &robot.twin->rig()};
  } else if (robot.lockstep) {
    robot.lockstep_truth_rig = std::make_unique<sim::StereoRig>(&robot.lockstep->world());
    robot.truth_world = TruthWorld{&robot.lockstep->world(), robot.lockstep_truth_rig.get()};
  }
  // A stock SensorHand measures no finger position: its driver integrates the commanded speeds
  // from an assumed start. A real hand that holds nothing opens to its end stop, where the
  // opening is known exactly; one that grips (a box held since the last run) keeps gripping.
  for (Side side : {Side::kLeft, Side::kRight}) {
    const std::string key = "hand_" + std::string(device::ToString(side));
    if (robot.start_failure || scenario.devices.Backend<cfg::SensorHandBackend>(key) == nullptr) {
      continue;
    }
    auto& hand =
        dynamic_cast<drivers::SensorHandHand&>(*robot.devices.hand[static_cast<int>(side)]);
    device::HandState state;
    device::Status s = hand.Read(&state);
    if (s == device::Status::kOk && state.grip_force_n < kHoldingForceN) {
      spdlog::info("{}: opening to the end stop (the driver's opening estimate is exact there)",
                   key);
      s = hand.Home();
      // Up to 3 s, in the driver's clock, looking at the stop request every 50 ms; a link that
      // fails meanwhile ends the wait.
      for (int i = 0; s == device::Status::kOk && i < 60 && !StopRequested(stop); ++i) {
        if (hand.WaitIdle(0.05)) break;
        s = hand.Read(&state);
      }
    }
    if (s != device::Status::kOk) {
      robot.start_failure = StartFailure{
          key, s, key + ": " + std::string(device::ToString(s)) + " while opening to the end stop"};
    }
  }
  // A freshly powered Biclops does not know where its axes are (relative encoders).
  const auto* head_config = scenario.devices.Backend<cfg::BiclopsBackend>("head");
  if (!robot.start_failure && head_config != nullptr && head_config->options.home_at_start) {
    auto& head = dynamic_cast<drivers::BiclopsHead&>(*robot.devices.head);
    spdlog::info("head: homing the Biclops (configure, then tilt, verge, pan)");
    const device::Status s = head.ConfigureAndHome(stop);
    if (s != device::Status::kOk) {
      robot.start_failure =
          StartFailure{"head", s,
                       s == device::Status::kInterrupted
                           ? (stop != nullptr ? stop->Reason() : "stop") + " during the homing"
                           : "head: " + std::string(device::ToString(s)) + " while homing (" +
                                 head.last_error() + ")"};
    }
  }
  return robot;
}

namespace {

using LinkOpener = std::function<std::unique_ptr<drivers::ByteLink>(const std::string& key)>;

// The real serial drivers `c` names, on the links `open` gives for their keys, reading `clock`,
// into `dev`; the laser board's driver (the cameras take its latches), null when none.
std::shared_ptr<drivers::LaserBoard> MakeSerialDrivers(const cfg::DevicesConfig& c,
                                                       const LinkOpener& open, Clock& clock,
                                                       device::RobotDevices* dev) {
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int i = static_cast<int>(side);
    const std::string name(device::ToString(side));
    if (const auto* arm = c.Backend<cfg::Val2Backend>("arm_" + name)) {
      dev->arm[i] = std::make_unique<drivers::Val2Arm>(open("arm_" + name), arm->options, clock);
    }
    if (const auto* hand = c.Backend<cfg::SensorHandBackend>("hand_" + name)) {
      dev->hand[i] =
          std::make_unique<drivers::SensorHandHand>(open("hand_" + name), hand->options, clock);
    }
  }
  if (const auto* head = c.Backend<cfg::BiclopsBackend>("head")) {
    dev->head = std::make_unique<drivers::BiclopsHead>(open("head"), head->options, clock);
  }
  // The laser and the LEDs hang on one board: one driver for both when both are real (the
  // loader has checked that they share the port and its settings; the laser's options win).
  std::shared_ptr<drivers::LaserBoard> board;
  for (const char* key : {"laser", "leds"}) {
    if (const auto* b = c.Backend<cfg::LaserBoardBackend>(key); b != nullptr && !board) {
      board = std::make_shared<drivers::LaserBoard>(open(key), b->options, clock);
    }
  }
  if (c.Backend<cfg::LaserBoardBackend>("laser")) {
    dev->laser = std::make_unique<drivers::BoardStripeLaser>(board);
  }
  if (c.Backend<cfg::LaserBoardBackend>("leds")) {
    dev->leds = std::make_unique<drivers::BoardLeds>(board);
  }
  return board;
}

// Lockstep: every driver on the twin's in-process lines, the twin's cameras.
device::RobotDevices MakeLockstepDevices(const sim::Scenario& s, Robot& robot) {
  device::RobotDevices dev;
  const LinkOpener open = [&robot](const std::string& key) {
    return robot.lockstep->HostLink(key == "laser" || key == "leds" ? "laser_board" : key);
  };
  std::shared_ptr<drivers::LaserBoard> board =
      MakeSerialDrivers(s.devices, open, *robot.clock, &dev);
  sim::Twin* twin = robot.lockstep.get();
  dev.cameras = std::make_unique<sim::LockstepCamera>(
      *robot.clock, robot.frames, [twin] { return twin->Develop(); },
      drivers::BoardLatchSource(board), dev.head.get());
  return dev;
}

}  // namespace

device::RobotDevices MakeDevices(const sim::Scenario& s, sim::SimRobot* twin) {
  const cfg::DevicesConfig& c = s.devices;
  HGRASP_DEMAND_MSG(twin != nullptr || !c.AnySimulated(),
                    "MakeDevices needs the simulated robot when a device is simulated");
  device::RobotDevices dev;
  if (twin != nullptr) dev = twin->TakeDevices();
  std::shared_ptr<drivers::LaserBoard> board = MakeSerialDrivers(
      c, [&s](const std::string& key) { return OpenPort(s, key); }, Clock::Wall(), &dev);
  if (const auto* cameras = c.Backend<cfg::GstreamerBackend>("cameras")) {
    // The scenario loader has checked that the laser is on the board.
    drivers::LatchSource latch = drivers::BoardLatchSource(board);
    std::string error;
    auto camera = drivers::GstStereoCamera::Open(cameras->cameras, latch, dev.head.get(), &error);
    if (!camera) {
      throw InputError(Where(s, *c.Find("cameras")), "devices.cameras",
                       error.rfind("left", 0) == 0 ? cameras->cameras.left : cameras->cameras.right,
                       "GStreamer pipelines that open (" + error + ")");
    }
    dev.cameras = std::move(camera);
  }
  return dev;
}

nlohmann::json CommandLogs(const device::RobotDevices& devices) {
  nlohmann::json logs = nlohmann::json::object();
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int i = static_cast<int>(side);
    const std::string name(device::ToString(side));
    if (const auto* arm = dynamic_cast<const drivers::Val2Arm*>(devices.arm[i].get())) {
      logs["arm_" + name] =
          LogJson(arm->command_log(), [](const std::string& line) { return nlohmann::json(line); });
    }
    if (const auto* hand = dynamic_cast<const drivers::SensorHandHand*>(devices.hand[i].get())) {
      logs["hand_" + name] =
          LogJson(hand->command_log(), [](const drivers::sensorhand::Command& c) {
            return nlohmann::json(drivers::HexBytes(drivers::sensorhand::Encode(c)));
          });
    }
  }
  if (const auto* head = dynamic_cast<const drivers::BiclopsHead*>(devices.head.get())) {
    logs["head"] = LogJson(head->command_log(), [](const drivers::pmd::Command& c) {
      return nlohmann::json{
          {"axis", c.axis}, {"opcode", c.opcode}, {"value", drivers::pmd::CommandValue(c)}};
    });
  }
  // The laser and the LEDs are one board with one driver (MakeDevices).
  const drivers::LaserBoard* board = nullptr;
  if (const auto* laser = dynamic_cast<const drivers::BoardStripeLaser*>(devices.laser.get())) {
    board = laser->board().get();
  } else if (const auto* leds = dynamic_cast<const drivers::BoardLeds*>(devices.leds.get())) {
    board = leds->board().get();
  }
  if (board != nullptr) {
    logs["laser_board"] = LogJson(board->command_log(), [](const drivers::laser_board::Command& c) {
      return nlohmann::json(drivers::HexBytes(drivers::laser_board::CommandPayload(c)) + "/" +
                            std::to_string(static_cast<int>(drivers::laser_board::CodeOf(c))));
    });
  }
  return logs;
}

}  // namespace hgrasp::app
