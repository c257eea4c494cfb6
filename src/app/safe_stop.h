#pragma once
/// @file Leaving the robot safe (DESIGN.md rule 8) and the stop signals that ask for it.
///
/// Every command that drives devices ends through LeaveSafe, whatever happened: on success, on a
/// failure, on SIGINT or SIGTERM (StopSignals turns them into a StopRequest that the scan and
/// the task poll at every frame), and when an exception unwinds the command (app::Robot's
/// destructor). The report names why the command ended and what each device answered to the
/// safe stop.

#include <signal.h>

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/stop_request.h"
#include "device/robot_devices.h"

namespace hgrasp::app {

/// What one device was told by the safe stop and what it answered.
struct SafeStopAction {
  std::string device;  ///< a devices key: "arm_left", "laser", ...
  std::string action;  ///< "stop", "laser off", "motor stop", "off"
  device::Status status = device::Status::kOk;
};

struct SafeStopReport {
  std::vector<SafeStopAction> actions;

  /// Whether every device took its command.
  bool ok() const;
  /// {"arm_left": {"stop": "ok"}, "laser": {"laser off": "ok", "motor stop": "ok"}, ...}
  nlohmann::json Json() const;
  /// "arm_right stop: timeout; ..." for the devices that did not take it ("" when all did).
  std::string Failures() const;
};

/// Both arms stopped (VAL II: ABORT), the laser off and its motor stopped, the LEDs of both
/// grippers off, the head stopped. The hands are told nothing: a hand that holds an object
/// keeps holding it, and an open hand stays open. Every device is told even when another does
/// not answer; a device that is absent (null) is skipped.
SafeStopReport LeaveSafe(device::RobotDevices& dev);

/// Turns SIGINT and SIGTERM into a StopRequest while it exists (the handlers it replaced are put
/// back when it goes). One at a time per process.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  const StopRequest* request() const { return &request_; }

 private:
  StopRequest request_;
  std::array<struct sigaction, 2> old_{};  // SIGINT's and SIGTERM's previous handlers
};

}  // namespace hgrasp::app
