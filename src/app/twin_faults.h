#pragma once
/// @file What a user asks of the twin's wires, shared by `hgrasp twin` (wall-clock time) and
/// `hgrasp run --lockstep` (simulated time): faults on every serial line (a FaultPlan drawn from
/// the scenario's seed, or --fault-seed) and control commands at given twin times (Twin::Control:
/// cut, mend, vanish, ... a line; stop or resume the cameras).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "serial/faulty_link.h"
#include "sim/scenario.h"
#include "sim/twin/twin.h"

namespace hgrasp::app {

struct TwinWireOptions {
  double corrupt = 0.0;         ///< per byte and direction, on every serial line
  double dropouts_per_s = 0.0;  ///< mean rate of dropouts on every serial line
  double dropout_s = 0.2;       ///< length of a dropout (s)
  /// Least time a line works between two dropouts (s); unset: one dropout's length, so that
  /// every outage is one dropout long (FaultPlan::min_dropout_gap_s).
  std::optional<double> dropout_gap_s;
  /// The faults' seed; unset: drawn from the scenario's (seed * 1000003 + 17).
  std::optional<std::uint64_t> fault_seed;
  std::vector<std::string> at;  ///< "SECONDS:COMMAND" (Twin::Control) at that twin time

  /// Any fault or command asked for.
  bool any() const { return corrupt > 0.0 || dropouts_per_s > 0.0 || !at.empty(); }
};

/// A control command at a twin time (seconds since the twin started).
struct ScheduledControl {
  double t_s = 0.0;
  std::string command;
};

/// Checks every field (hgrasp::InputError naming the option: --corrupt, --dropouts, --dropout-s,
/// --dropout-gap-s, --at) and returns the schedule of --at, in the order given.
std::vector<ScheduledControl> CheckTwinWires(const TwinWireOptions& o);

/// The fault plan of every line (each line varies its seed from it), or none without faults.
std::optional<drivers::FaultPlan> FaultPlanFor(const TwinWireOptions& o,
                                               const sim::Scenario& scenario);

/// The twin's seed and its lines' faults for a scenario, the same for `hgrasp twin` and
/// `run --lockstep` (so that one scenario and fault seed make the same twin either way): the
/// twin draws its own errors from the scenario's seed + 1 (the pipeline's simulated devices
/// draw from the seed itself).
sim::TwinOptions TwinOptionsFor(const TwinWireOptions& o, const sim::Scenario& scenario);

}  // namespace hgrasp::app
