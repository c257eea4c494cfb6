#include "app/twin_faults.h"

#include <cmath>
#include <cstdlib>

#include "common/error.h"

namespace hgrasp::app {

std::vector<ScheduledControl> CheckTwinWires(const TwinWireOptions& o) {
  if (!(o.corrupt >= 0.0 && o.corrupt < 0.5)) {
    throw InputError("", "--corrupt", std::to_string(o.corrupt), "a probability in [0, 0.5)");
  }
  if (!(o.dropouts_per_s >= 0.0 && o.dropouts_per_s <= 10.0)) {
    throw InputError("", "--dropouts", std::to_string(o.dropouts_per_s),
                     "dropouts per second, 0-10");
  }
  if (!(o.dropout_s > 0.0 && o.dropout_s <= 5.0)) {
    throw InputError("", "--dropout-s", std::to_string(o.dropout_s), "seconds, > 0 and <= 5");
  }
  if (o.dropout_gap_s && !(*o.dropout_gap_s >= 0.0 && *o.dropout_gap_s <= 60.0)) {
    throw InputError("", "--dropout-gap-s", std::to_string(*o.dropout_gap_s), "seconds, 0-60");
  }
  std::vector<ScheduledControl> v;
  for (const std::string& a : o.at) {
    const size_t colon = a.find(':');
    char* end = nullptr;
    const double t = colon == std::string::npos ? -1.0 : std::strtod(a.c_str(), &end);
    if (colon == std::string::npos || end != a.c_str() + colon || !(t >= 0.0) ||
        !std::isfinite(t)) {
      throw InputError("", "--at", a, "SECONDS:COMMAND, e.g. 12.5:cut arm_right");
    }
    v.push_back({t, a.substr(colon + 1)});
  }
  return v;
}

std::optional<drivers::FaultPlan> FaultPlanFor(const TwinWireOptions& o,
                                               const sim::Scenario& scenario) {
  if (!(o.corrupt > 0.0 || o.dropouts_per_s > 0.0)) return std::nullopt;
  drivers::FaultPlan plan;
  plan.corrupt_probability = o.corrupt;
  plan.dropouts_per_s = o.dropouts_per_s;
  plan.dropout_s = o.dropout_s;
  plan.min_dropout_gap_s = o.dropout_gap_s.value_or(o.dropout_s);
  plan.seed = o.fault_seed.value_or(scenario.seed * 1000003u + 17u);
  return plan;
}

sim::TwinOptions TwinOptionsFor(const TwinWireOptions& o, const sim::Scenario& scenario) {
  sim::TwinOptions options;
  options.seed = scenario.seed + 1;
  options.faults = FaultPlanFor(o, scenario);
  return options;
}

}  // namespace hgrasp::app
