// `hgrasp emulate DEVICE`: one device emulator on a pseudo-terminal, for trying the real drivers
// (or a terminal program) without the hardware. Prints the port's path, serves until SIGINT or
// SIGTERM (or --seconds).

#include <signal.h>

#include <chrono>
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
  if (o.seconds > 0.0) {
    const timespec wait{static_cast<time_t>(o.seconds),
                        static_cast<long>((o.seconds - static_cast<time_t>(o.seconds)) * 1e9)};
    sigtimedwait(&stop, nullptr, &wait);
  } else {
    int sig = 0;
    sigwait(&stop, &sig);
  }
  return 0;
}

}  // namespace hgrasp::app
