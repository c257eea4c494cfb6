// The physics step of the default scene (MuJoCo, 2 ms steps, elliptic cones, the noslip solver
// of models/humanoid.xml), boxes resting on the table: what the twin's clock must keep up with.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "sim/world.h"

namespace hgrasp::sim {
namespace {

void BM_PhysicsStep100ms(benchmark::State& state) {
  setenv("HGRASP_ROOT", HGRASP_SOURCE_ROOT, 0);
  World world(LoadScenario(std::string(HGRASP_SOURCE_ROOT) + "/scenarios/default.yaml"));
  for (auto _ : state) world.Step(0.1);
  state.counters["sim_s"] = benchmark::Counter(
      0.1 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PhysicsStep100ms)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hgrasp::sim
