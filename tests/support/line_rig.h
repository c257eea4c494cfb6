#pragma once
/// @file What the drivers' protocol tests stand on: a device's emulator at the far end of a
/// simulated serial line (drivers::SimLine: bytes paced at the baud rate, the faults of a plan),
/// its host end for the driver, all on one SimClock, so that every run of a case is the same run
/// whatever the machine is doing. A driver's own rig derives from it and adds the driver.
///   struct Rig : hgrasp::testing::LineRig<Val2Emulator> {
///     Rig() : LineRig(MakeVal2Emulator(), 9600), arm(Open(), {}, clock) {}
///     Val2Arm arm;
///   };
///   rig.With([](Val2Emulator& e) { return e.executed(); });

#include <memory>
#include <optional>
#include <utility>

#include "common/clock.h"
#include "emulators/emulator.h"
#include "emulators/sim_line.h"
#include "serial/byte_link.h"
#include "serial/faulty_link.h"

namespace hgrasp::testing {

/// Runs f(emulator) on `line`'s device as an `Emulator` (which it must be).
template <class Emulator, class F>
auto WithEmulator(drivers::SimLine& line, F&& f) {
  return line.With([&](drivers::DeviceEmulator& d) { return f(dynamic_cast<Emulator&>(d)); });
}

template <class Emulator>
class LineRig {
 public:
  /// `faults`: none when nullopt.
  LineRig(std::unique_ptr<Emulator> emulator, int baud,
          std::optional<drivers::FaultPlan> faults = std::nullopt)
      : line_(clock, std::move(emulator), baud, std::move(faults)) {}

  /// The driver's end of the line (the rig must outlive it).
  std::unique_ptr<drivers::ByteLink> Open() { return line_.Open(); }
  drivers::SimLine& line() { return line_; }

  /// Runs f(emulator): to inspect or script the device (nothing runs meanwhile).
  template <class F>
  auto With(F&& f) {
    return WithEmulator<Emulator>(line_, std::forward<F>(f));
  }

  /// Simulated seconds since `t0`.
  double Since(Clock::TimePoint t0) const { return Clock::ToSeconds(clock.Now() - t0); }

  SimClock clock;  // declared first: the line runs on it

 private:
  drivers::SimLine line_;
};

}  // namespace hgrasp::testing
