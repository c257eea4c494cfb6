#pragma once
/// @file The twin behind the real wires on a thread, for the tests and benchmarks that talk to
/// it through the real drivers: a scenario's world in wall-clock time (sim::Twin::Run), its
/// cameras on a GstStereoServer, and the real LaserBoard, GstStereoCamera (latch_pairing
/// offset, its latches from that board) and Val2Arm (arm_right) on its ports, opened as
/// src/app/devices.cc opens them.

#include <stdlib.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "camera/gst_stereo_camera.h"
#include "camera/gst_stereo_server.h"
#include "laser_board/board_devices.h"
#include "laser_board/laser_board.h"
#include "serial/serial_port.h"
#include "sim/twin/twin.h"
#include "val2/val2_arm.h"

namespace hgrasp::sim::testing {

namespace fs = std::filesystem;
using device::Status;
using Clock = std::chrono::steady_clock;

inline double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

inline int Baud(const char* key) {
  for (const TwinLineSpec& s : kTwinLines) {
    if (std::string(s.key) == key) return s.baud;
  }
  return 0;
}

// The twin of `scenario` on a thread, its camera server, and the real drivers on its wires,
// the streams connected (three frames through). `ok` false (and `error` why) when something
// did not open.
struct TwinRig {
  std::string dir;
  std::unique_ptr<drivers::GstStereoServer> server;
  std::unique_ptr<Twin> twin;
  std::atomic<bool> stop{false};
  std::thread runner;
  std::shared_ptr<drivers::LaserBoard> board;
  std::unique_ptr<drivers::BoardStripeLaser> laser;
  std::unique_ptr<drivers::GstStereoCamera> camera;
  std::unique_ptr<drivers::Val2Arm> arm;
  bool ok = false;
  std::string error;

  explicit TwinRig(const std::string& scenario) {
    std::string t = (fs::temp_directory_path() / "twin_rig_XXXXXX").string();
    if (::mkdtemp(t.data()) == nullptr) {
      error = "no temporary folder";
      return;
    }
    dir = t;
    server = drivers::GstStereoServer::Open("127.0.0.1", 0, 0, 320, 240, &error);
    if (!server) return;
    drivers::GstStereoServer* srv = server.get();
    TwinOptions options;
    options.dir = dir;
    twin = std::make_unique<Twin>(
        LoadScenario(scenario), options,
        [srv](int camera, const cv::Mat& bgr, std::uint64_t frame, double t) {
          srv->Push(camera, bgr, frame, t);
        });
    runner = std::thread([this] { twin->Run([this] { return !stop.load(); }); });
    auto open = [this](const char* key) -> std::unique_ptr<drivers::SerialPort> {
      drivers::SerialConfig serial;
      serial.port = dir + "/" + key;
      serial.baud = Baud(key);
      return drivers::SerialPort::Open(serial, &error);
    };
    std::unique_ptr<drivers::SerialPort> board_port = open("laser_board");
    if (!board_port) return;
    board = std::make_shared<drivers::LaserBoard>(std::move(board_port));
    laser = std::make_unique<drivers::BoardStripeLaser>(board);
    std::unique_ptr<drivers::SerialPort> arm_port = open("arm_right");
    if (!arm_port) return;
    arm = std::make_unique<drivers::Val2Arm>(std::move(arm_port));
    drivers::LatchSource latch = drivers::BoardLatchSource(board);
    drivers::GstCameraConfig config;
    config.left = server->ClientPipeline(0);
    config.right = server->ClientPipeline(1);
    config.latch_pairing = drivers::LatchPairing::kOffset;
    camera = drivers::GstStereoCamera::Open(config, latch, nullptr, &error);
    if (!camera) return;
    // The streams connect: the first frames that come through.
    device::StereoFrame frame;
    int got = 0;
    const Clock::time_point t0 = Clock::now();
    while (got < 3 && Since(t0) < 10.0) {
      if (camera->Grab(&frame) == Status::kOk) ++got;
    }
    if (got < 3) {
      error = "no frames from the twin within 10 s: " + camera->last_error();
      return;
    }
    ok = true;
  }
  // Stops the twin (its exposures and logs may be read after).
  void StopTwin() {
    stop = true;
    if (runner.joinable()) runner.join();
  }
  ~TwinRig() {
    camera.reset();
    arm.reset();
    laser.reset();
    board.reset();
    StopTwin();
    twin.reset();
    server.reset();
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
};

}  // namespace hgrasp::sim::testing
