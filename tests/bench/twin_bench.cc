// The twin behind the real wires (sim/twin/) as the real drivers see it: the twin runs the
// default scenario in wall-clock time on a thread, streams its cameras through GstStereoServer
// and serves its serial devices on ptys; the real GstStereoCamera (latch_pairing offset, the
// latches from the real LaserBoard driver) and the real Val2Arm (arm_right, 9600 baud) talk to
// it. Both cases run once (Iterations(1)) and report manual counters.

#include <benchmark/benchmark.h>
#include <stdlib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "../sim/twin/twin_rig.h"
#include "camera/gst_stereo_camera.h"
#include "camera/gst_stereo_server.h"
#include "common/error.h"
#include "emulators/val2_emulator.h"
#include "laser_board/board_devices.h"
#include "laser_board/laser_board.h"
#include "serial/serial_port.h"
#include "sim/twin/twin.h"
#include "val2/val2_arm.h"

namespace hgrasp::sim {
namespace {

using device::Status;
using testing::Clock;
using testing::Since;
using testing::TwinRig;

// (a) Frames through to the driver for ~8 s, the laser on and sweeping back and forth between
// its limits at the argument's speed (counts/s): 400, the scanner's sweep (4800 counts in 300
// frames), and 9000, full speed. Counters: pairs per second of wall time the driver returns,
// frames lost on the way (gaps in the frame numbers: they include the twin's overruns), and the
// twin's exposures, renders, overruns and render times (since its start, a second before the
// 8 s). At full speed each reversal moves the head's joints by 1-2 urad (the reaction of the
// laser's ramp), over the render cache's tolerance: a full re-render each time (50-150 ms on
// llvmpipe, more when the CPUs are busy), and overruns.
void BM_TwinFramesToTheDriver(benchmark::State& state) {
  for (auto _ : state) {
    setenv("HGRASP_ROOT", HGRASP_SOURCE_ROOT, 0);
    TwinRig rig(std::string(HGRASP_SOURCE_ROOT) + "/scenarios/default.yaml");
    if (!rig.ok) {
      state.SkipWithError(rig.error.c_str());
      return;
    }
    const double speed = static_cast<double>(state.range(0));
    std::int32_t target = 4500;
    HGRASP_DEMAND(rig.laser->SetLaser(true) == device::Status::kOk);
    HGRASP_DEMAND(rig.laser->MoveTo(target, speed) == device::Status::kOk);
    const drivers::GstCameraStats s0 = rig.camera->stats();
    device::StereoFrame frame;
    int failed = 0;
    const Clock::time_point t0 = Clock::now();
    while (Since(t0) < 8.0) {
      if (rig.camera->Grab(&frame) != Status::kOk) {
        ++failed;
        continue;
      }
      device::StripeLaserState st;
      if (rig.laser->Read(&st) == Status::kOk && !st.moving) {
        target = -target;
        HGRASP_DEMAND(rig.laser->MoveTo(target, speed) == device::Status::kOk);
      }
    }
    const double wall = Since(t0);
    const drivers::GstCameraStats s1 = rig.camera->stats();
    HGRASP_DEMAND(rig.laser->Stop() == device::Status::kOk);
    HGRASP_DEMAND(rig.laser->SetLaser(false) == device::Status::kOk);
    rig.StopTwin();
    const TwinFrameCounts c = rig.twin->frame_counts();
    state.counters["frames_per_s"] = static_cast<double>(s1.pairs - s0.pairs) / wall;
    state.counters["lost_left"] = static_cast<double>(s1.frames_lost[0] - s0.frames_lost[0]);
    state.counters["lost_right"] = static_cast<double>(s1.frames_lost[1] - s0.frames_lost[1]);
    state.counters["unpaired"] =
        static_cast<double>(s1.unpaired[0] - s0.unpaired[0] + s1.unpaired[1] - s0.unpaired[1]);
    state.counters["failed_grabs"] = failed;
    state.counters["exposures"] = static_cast<double>(c.exposures);
    state.counters["rendered"] = static_cast<double>(c.rendered);
    state.counters["overruns"] = static_cast<double>(c.overruns);
    state.counters["render_mean_ms"] = c.rendered ? 1e3 * c.render_s / c.rendered : 0.0;
    state.counters["render_max_ms"] = 1e3 * c.max_render_s;
    state.counters["max_lag_ms"] = 1e3 * c.max_lag_s;
  }
}
BENCHMARK(BM_TwinFramesToTheDriver)
    ->Arg(400)
    ->Arg(9000)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// (b) From a frame's exposure to the arm's controller executing a command sent on it: Grab a
// frame (t_s = its exposure on the twin's clock), send a tiny tool-relative move (0.5 mm along
// x, alternating) at once, and pair the command with the time the twin's VAL II emulator
// executed it (its CR, twin clock). The latency includes the frame's rendering and transport
// (GStreamer over loopback TCP), the driver's latch request to the laser board, and Val2Arm's
// typing of the command at 9600 baud with its echo check and ^R confirmation (about 40
// characters each way): it is what a servo loop on the real wires would see. Before each Grab
// the arm's move is waited out (Read until !moving) so that the commands do not pile up, and one
// frame is grabbed and dropped so that the frame used is one that has just arrived, not the
// one the camera's one-frame queue kept during the wait.
void BM_TwinExposureToArmCommand(benchmark::State& state) {
  for (auto _ : state) {
    setenv("HGRASP_ROOT", HGRASP_SOURCE_ROOT, 0);
    TwinRig rig(std::string(HGRASP_SOURCE_ROOT) + "/scenarios/default.yaml");
    if (!rig.ok) {
      state.SkipWithError(rig.error.c_str());
      return;
    }
    constexpr int kCommands = 20;
    std::vector<double> exposure_s, call_ms;
    int failed = 0, timeouts = 0;
    device::StereoFrame frame;
    device::ArmState arm;
    if (rig.arm->Read(&arm) != Status::kOk) ++failed;
    double loop_t0 = -1.0;
    for (int i = 0; i < kCommands; ++i) {
      if (rig.camera->Grab(&frame) != Status::kOk || rig.camera->Grab(&frame) != Status::kOk) {
        ++failed;
        continue;
      }
      if (loop_t0 < 0.0) loop_t0 = frame.t_s;
      Pose3 X = Pose3::Identity();
      X.translation().x() = (i % 2 == 0 ? 1.0 : -1.0) * 0.0005;
      const Clock::time_point sent = Clock::now();
      if (rig.arm->MoveRelative(X) != Status::kOk) {
        ++failed;
        continue;
      }
      call_ms.push_back(1e3 * Since(sent));
      exposure_s.push_back(frame.t_s);
      const Clock::time_point t0 = Clock::now();
      for (;;) {
        if (rig.arm->Read(&arm) == Status::kOk && !arm.moving) break;
        if (Since(t0) > 5.0) {
          ++timeouts;
          break;
        }
      }
    }
    rig.StopTwin();
    const auto& val2 =
        dynamic_cast<const drivers::Val2Emulator&>(rig.twin->line("arm_right")->device());
    std::vector<double> executed;
    for (const drivers::Val2Executed& e : val2.executed()) {
      if (loop_t0 >= 0.0 && e.t_s >= loop_t0 &&
          (e.line.rfind("DO APPRO", 0) == 0 || e.line.rfind("DO MOVE", 0) == 0)) {
        executed.push_back(e.t_s);
      }
    }
    std::vector<double> latency;
    for (std::size_t i = 0; i < exposure_s.size() && i < executed.size(); ++i) {
      latency.push_back(1e3 * (executed[i] - exposure_s[i]));
    }
    double mean = 0.0, p95 = 0.0, max = 0.0;
    if (!latency.empty()) {
      for (double l : latency) mean += l / static_cast<double>(latency.size());
      std::vector<double> sorted = latency;
      std::sort(sorted.begin(), sorted.end());
      // Nearest rank: with 20 commands the 19th.
      const auto rank =
          static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(sorted.size())));
      p95 = sorted[std::max<std::size_t>(rank, 1) - 1];
      max = sorted.back();
    }
    state.counters["commands"] = static_cast<double>(exposure_s.size());
    state.counters["executed"] = static_cast<double>(executed.size());
    state.counters["failed"] = failed;
    state.counters["settle_timeouts"] = timeouts;
    double call_mean = 0.0;
    for (double c : call_ms) call_mean += c / static_cast<double>(call_ms.size());
    // How long MoveRelative took (wall): the typing at 9600 baud, the echo checks, the ^R
    // confirmation and the CR's answer. The rest of the latency is the frame's age when Grab
    // returned it (render, transport, the latch request).
    state.counters["move_call_mean_ms"] = call_mean;
    state.counters["latency_mean_ms"] = mean;
    state.counters["latency_p95_ms"] = p95;
    state.counters["latency_max_ms"] = max;
    if (executed.size() != exposure_s.size()) {
      state.SkipWithError("the commands sent and the moves the controller executed differ");
    }
  }
}
BENCHMARK(BM_TwinExposureToArmCommand)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hgrasp::sim
