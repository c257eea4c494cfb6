// Scanner benchmarks: one stereo frame pair through rectification, stripe detection, validation
// and reconstruction on one core (target: at least 1000 pairs per second, 40 times the
// cameras' 25 Hz); and a whole `hgrasp scan` sweep of the default scenario.

#include <benchmark/benchmark.h>

#include <cstdlib>

#include "common/error.h"
#include "common/paths.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "sim/sim_devices.h"

namespace hgrasp::scan {
namespace {

struct Setup {
  std::unique_ptr<sim::SimRobot> robot;
  device::RobotDevices dev;
  std::unique_ptr<Scanner> scanner;
};

Setup Make() {
  setenv("HGRASP_ROOT", HGRASP_SOURCE_ROOT, 0);
  Setup s;
  s.robot =
      std::make_unique<sim::SimRobot>(sim::LoadScenario(ResolveDataPath("scenarios/default.yaml")));
  s.dev = s.robot->TakeDevices();
  s.scanner = std::make_unique<Scanner>(
      robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf")),
      robot::LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml")),
      robot::LoadLaserCalibration(ResolveDataPath("calibration/sim/laser.yaml")));
  return s;
}

// Frames of a real sweep, processed again and again.
void BM_StripeFramePair(benchmark::State& state) {
  Setup s = Make();
  std::vector<device::StereoFrame> frames;
  device::StereoFrame ambient;
  HGRASP_DEMAND(s.dev.laser->SetLaser(false) == device::Status::kOk);
  HGRASP_DEMAND(s.dev.cameras->Grab(&ambient) == device::Status::kOk);
  HGRASP_DEMAND(s.dev.laser->SetLaser(true) == device::Status::kOk);
  HGRASP_DEMAND(Sweep(s.dev, {2400, -2400, 60}, [&](const device::StereoFrame& f) {
                  frames.push_back(f);
                }) == device::Status::kOk);
  RangeImage range(240, 1);
  StripeFrameResult result;
  size_t i = 0, points = 0;
  for (auto _ : state) {
    s.scanner->ProcessFrame(frames[i % frames.size()], ambient, &range, 0, &result);
    points += result.points.size();
    ++i;
  }
  state.SetItemsProcessed(static_cast<int64_t>(i));
  state.counters["points_per_frame"] = static_cast<double>(points) / i;
}
BENCHMARK(BM_StripeFramePair)->Unit(benchmark::kMicrosecond);

void BM_WholeScan(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    Setup s = Make();
    state.ResumeTiming();
    const ScanResult r = s.scanner->Scan(s.dev, {});
    state.counters["points"] = r.points;
  }
}
BENCHMARK(BM_WholeScan)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
}  // namespace hgrasp::scan
