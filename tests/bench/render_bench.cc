// Rendering benchmarks on whatever renders here (Mesa's llvmpipe on the 2-core CI machine):
// one stereo frame, rendered in full and composited from the per-head-pose cache, and a
// 300-position laser sweep through the devices (target: at most 2 s wall).

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>

#include "common/error.h"
#include "sim/sim_devices.h"

namespace hgrasp::sim {
namespace {

std::unique_ptr<SimRobot> DefaultRobot() {
  setenv("HGRASP_ROOT", HGRASP_SOURCE_ROOT, 0);
  return std::make_unique<SimRobot>(
      LoadScenario(std::string(HGRASP_SOURCE_ROOT) + "/scenarios/default.yaml"));
}

void BM_StereoFrameFullRender(benchmark::State& state) {
  auto robot = DefaultRobot();
  robot->world().set_laser_on(true);
  robot->rig().set_cache_enabled(false);
  std::uint64_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(robot->rig().Expose(k++));
  state.SetLabel(robot->rig().renderer().DeviceDescription());
}
BENCHMARK(BM_StereoFrameFullRender)->Unit(benchmark::kMillisecond)->UseRealTime();

// The servo's frames: laser off, the arm moving (cache off), colour only.
void BM_StereoFrameColourOnly(benchmark::State& state) {
  auto robot = DefaultRobot();
  robot->rig().set_cache_enabled(false);
  std::uint64_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(robot->rig().Expose(k++));
}
BENCHMARK(BM_StereoFrameColourOnly)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_StereoFrameComposited(benchmark::State& state) {
  auto robot = DefaultRobot();
  robot->world().set_laser_on(true);
  std::uint64_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(robot->rig().Expose(k++));
}
BENCHMARK(BM_StereoFrameComposited)->Unit(benchmark::kMillisecond)->UseRealTime();

// A scan: the laser crosses the workspace (-24 to +24 deg) in 300 frames, 40 ms of simulated
// time each, through the device seam as the scanner will drive it.
void BM_Sweep300(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    auto robot = DefaultRobot();
    auto dev = robot->TakeDevices();
    HGRASP_DEMAND(dev.laser->SetLaser(true) == device::Status::kOk);
    HGRASP_DEMAND(dev.laser->MoveTo(-2400, 90000) == device::Status::kOk);
    device::StereoFrame frame;
    for (int i = 0; i < 60; ++i)
      HGRASP_DEMAND(dev.cameras->Grab(&frame) == device::Status::kOk);  // reach the start
    const int renders_before = robot->rig().full_renders();
    state.ResumeTiming();
    HGRASP_DEMAND(dev.laser->MoveTo(2400, 4800 / (300 * 0.04)) == device::Status::kOk);
    for (int i = 0; i < 300; ++i) HGRASP_DEMAND(dev.cameras->Grab(&frame) == device::Status::kOk);
    benchmark::DoNotOptimize(frame);
    state.counters["renders_in_sweep"] = robot->rig().full_renders() - renders_before;
  }
}
BENCHMARK(BM_Sweep300)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace hgrasp::sim
