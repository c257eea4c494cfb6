// `hgrasp emulate DEVICE`: one device emulator on a pseudo-terminal, for trying the real drivers
// (or a terminal program) without the hardware. Prints the port's path, serves until SIGINT or
// SIGTERM (or --seconds).

#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "app/commands.h"
#include "common/error.h"
#include "emulators/biclops_emulator.h"
#include "emulators/emulator.h"
#include "emulators/laser_board_emulator.h"
#include "emulators/sensorhand_emulator.h"
#include "emulators/val2_emulator.h"

namespace hgrasp::app {

namespace {

std::unique_ptr<drivers::DeviceEmulator> MakeEmulator(const EmulateOptions& o) {
  if (o.device == "val2") {
    return drivers::MakeVal2Emulator(o.side == "left" ? device::Side::kLeft : device::Side::kRight);
  }
  if (o.device == "biclops") return drivers::MakeBiclopsEmulator();
  if (o.device == "sensorhand") return drivers::MakeSensorHandEmulator();
  if (o.device == "laser_board") return drivers::MakeLaserBoardEmulator();
  throw InputError("", "DEVICE", o.device, "val2, biclops, sensorhand or laser_board");
}

}  // namespace

int Emulate(const EmulateOptions& o) {
  if (o.side != "left" && o.side != "right") {
    throw InputError("", "--side", o.side, "left or right");
  }
  if (o.seconds && !(std::isfinite(*o.seconds) && *o.seconds > 0.0 &&
                     *o.seconds <= kMaxEmulateSeconds)) {
    char value[32];
    std::snprintf(value, sizeof value, "%g", *o.seconds);
    throw InputError("", "--seconds", value,
                     "a time in seconds, > 0 and at most 1e6 (leave it out to serve until Ctrl-C)");
  }
  std::unique_ptr<drivers::DeviceEmulator> device = MakeEmulator(o);
  // Block the stop signals before any thread starts, then wait for one of them.
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGINT);
  sigaddset(&stop, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop, nullptr);
  std::unique_ptr<drivers::EmulatorHost> host;
  try {
    host = std::make_unique<drivers::EmulatorHost>(std::move(device), o.link);
  } catch (const std::runtime_error& e) {
    throw InputError("", "--link", o.link,
                     std::string("a path for the port's link (") + e.what() + ")");
  }
  std::printf("%s\n", host->port().c_str());
  std::fflush(stdout);
  if (o.seconds) {
    // Until the time is up or a stop signal comes (sigtimedwait may return early: EINTR).
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(*o.seconds);
    for (;;) {
      const double left =
          std::chrono::duration<double>(end - std::chrono::steady_clock::now()).count();
      if (left <= 0.0) break;
      const auto whole = static_cast<time_t>(left);
      const timespec wait{whole, static_cast<long>((left - static_cast<double>(whole)) * 1e9)};
      if (sigtimedwait(&stop, nullptr, &wait) >= 0) break;  // a stop signal
    }
  } else {
    int sig = 0;
    sigwait(&stop, &sig);
  }
  return 0;
}

}  // namespace hgrasp::app
