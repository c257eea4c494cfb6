#pragma once
// Test rigs: the emulated Biclops chip on a simulated 9600-baud line (SimLine) in simulated time
// (BiclopsLineRig), and BiclopsHead on its host end (BiclopsRig). A test whose driver needs more
// (a ByteLink between the line and the driver, another driver, no driver) takes BiclopsLineRig,
// wraps its Open() and makes the driver itself on the rig's clock.

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "biclops/biclops_head.h"
#include "emulators/biclops_emulator.h"
#include "serial/faulty_link.h"
#include "tests/support/line_rig.h"

namespace hgrasp::drivers::testing {

class BiclopsLineRig : public hgrasp::testing::LineRig<BiclopsEmulator> {
 public:
  /// The head's line (BiclopsOptions: 9600 8N1).
  static constexpr int kBaud = 9600;

  /// `faults`: the line's (none when nullopt).
  explicit BiclopsLineRig(const BiclopsEmulatorConfig& config = DefaultBiclopsEmulatorConfig(),
                          std::optional<FaultPlan> faults = std::nullopt)
      : LineRig(std::make_unique<BiclopsEmulator>(config), kBaud, std::move(faults)) {}

  /// The commands the chip executed, in order.
  std::vector<PmdExecuted> Log() {
    return With([](BiclopsEmulator& e) { return e.executed(); });
  }
  /// Where `axis` truly stands: the chip's position counter, counts.
  double ChipCounts(int axis) {
    return With([axis](BiclopsEmulator& e) { return e.chip().position_counts(axis); });
  }
  bool ChipMoving(int axis) {
    return With([axis](BiclopsEmulator& e) { return e.chip().moving(axis); });
  }
};

/// The line, and BiclopsHead straight on its host end.
struct BiclopsRig : BiclopsLineRig {
  explicit BiclopsRig(const BiclopsEmulatorConfig& config = DefaultBiclopsEmulatorConfig(),
                      const BiclopsOptions& options = DefaultBiclopsOptions())
      : BiclopsLineRig(config), head(Open(), options, clock) {}

  BiclopsHead head;  // declared after the line (in the base): it goes first
};

}  // namespace hgrasp::drivers::testing
