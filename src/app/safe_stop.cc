#include "app/safe_stop.h"

#include <atomic>

#include "common/error.h"

namespace hgrasp::app {
namespace {

using device::Side;
using device::Status;

std::atomic<StopRequest*> g_request{nullptr};

void OnStopSignal(int signal) {
  if (StopRequest* r = g_request.load()) r->Request(signal);
}

}  // namespace

bool SafeStopReport::ok() const {
  for (const SafeStopAction& a : actions) {
    if (a.status != Status::kOk) return false;
  }
  return true;
}

nlohmann::json SafeStopReport::Json() const {
  nlohmann::json j = nlohmann::json::object();
  for (const SafeStopAction& a : actions) j[a.device][a.action] = device::ToString(a.status);
  return j;
}

std::string SafeStopReport::Failures() const {
  std::string text;
  for (const SafeStopAction& a : actions) {
    if (a.status == Status::kOk) continue;
    text += (text.empty() ? "" : "; ") + a.device + " " + a.action + ": " +
            std::string(device::ToString(a.status));
  }
  return text;
}

SafeStopReport LeaveSafe(device::RobotDevices& dev) {
  SafeStopReport r;
  const auto add = [&](std::string device, std::string action, Status status) {
    r.actions.push_back({std::move(device), std::move(action), status});
  };
  // The arms first: they carry the most energy. What needs no answer goes out to both before
  // either waits on its line: at 9600 baud the left arm's confirmed ABORT took 56 ms, and the
  // right arm, whose controller had gone silent, got its blind ABORT 0.506 s after the cut.
  for (auto& arm : dev.arm) {
    if (arm) arm->StopAtOnce();
  }
  for (Side side : {Side::kLeft, Side::kRight}) {
    const std::string key = "arm_" + std::string(device::ToString(side));
    if (device::Arm* arm = dev.arm[static_cast<int>(side)].get()) {
      add(key, "stop", arm->SafeStop());
    }
  }
  if (dev.laser) {
    add("laser", "laser off", dev.laser->SetLaser(false));
    add("laser", "motor stop", dev.laser->Stop());
  }
  if (dev.leds) {
    for (Side side : {Side::kLeft, Side::kRight}) {
      add("leds", std::string(device::ToString(side)) + " off", dev.leds->Set(side, 0));
    }
  }
  if (dev.head) add("head", "stop", dev.head->Stop());
  return r;
}

StopSignals::StopSignals() {
  StopRequest* none = nullptr;
  HGRASP_DEMAND_MSG(g_request.compare_exchange_strong(none, &request_),
                    "one StopSignals at a time");
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking call returns EINTR and the caller polls
  sigaction(SIGINT, &sa, &old_[0]);
  sigaction(SIGTERM, &sa, &old_[1]);
}

StopSignals::~StopSignals() {
  sigaction(SIGINT, &old_[0], nullptr);
  sigaction(SIGTERM, &old_[1], nullptr);
  g_request.store(nullptr);
}

}  // namespace hgrasp::app
