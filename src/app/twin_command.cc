// `hgrasp twin SCENARIO`: the twin behind the real wires. The scenario's world runs in wall-clock
// time (or --rate slower); every serial device is served on its own protocol on a pty whose link
// is in --dir (arm_left, arm_right, hand_left, hand_right, head, laser_board), the cameras as
// two GStreamer streams (GDP over TCP on localhost). It writes into --dir:
//   devices.yaml   the devices block naming every real driver on these ports and pipelines
//   scenario.yaml  the scenario with that block: `hgrasp run DIR/scenario.yaml` runs against it
//   world.xml      the scenario's world as MJCF (MuJoCo's `simulate` opens it)
//   control        a FIFO: write "cut arm_right", "stop cameras", ... (Twin::Control)
//   ready          once everything serves
//   twin.json      at the end: frames, overruns, line counts, faults, truth, command logs
// and serves until SIGINT or SIGTERM (or --seconds).

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/commands.h"
#include "app/twin_faults.h"
#include "camera/gst_stereo_server.h"
#include "common/error.h"
#include "common/write_file.h"
#include "sim/scenario.h"
#include "sim/twin/twin.h"

namespace hgrasp::app {

namespace {

namespace fs = std::filesystem;

std::atomic<int> g_stop_signal{0};

void OnStopSignal(int sig) { g_stop_signal = sig; }

}  // namespace

int Twin(const TwinCommandOptions& o) {
  if (!(o.rate > 0.0 && o.rate <= 1.0)) {
    throw InputError("", "--rate", std::to_string(o.rate),
                     "twin seconds per wall second, > 0 and at most 1");
  }
  if (o.seconds && !(*o.seconds > 0.0 && std::isfinite(*o.seconds))) {
    throw InputError("", "--seconds", std::to_string(*o.seconds), "a time in seconds, > 0");
  }
  const std::vector<ScheduledControl> schedule = CheckTwinWires(o.wires);
  std::vector<bool> done(schedule.size(), false);
  sim::Scenario scenario = sim::LoadScenario(o.scenario);
  std::error_code ec;
  fs::create_directories(o.dir, ec);
  if (ec || !fs::is_directory(o.dir)) {
    throw InputError("", "--dir", o.dir, "a folder for the twin's ports (" + ec.message() + ")");
  }

  std::string error;
  std::unique_ptr<drivers::GstStereoServer> cameras = drivers::GstStereoServer::Open(
      o.camera_host, o.camera_ports[0], o.camera_ports[1], 320, 240, &error);
  if (!cameras) {
    throw InputError("", "--camera-ports",
                     std::to_string(o.camera_ports[0]) + "," + std::to_string(o.camera_ports[1]),
                     "TCP ports the camera streams can listen on (" + error + ")");
  }

  sim::TwinOptions options = TwinOptionsFor(o.wires, scenario);
  options.dir = fs::absolute(o.dir).lexically_normal().string();
  options.rate = o.rate;
  drivers::GstStereoServer* server = cameras.get();
  sim::FrameSink sink = [server](int camera, const cv::Mat& bgr, std::uint64_t frame,
                                 double exposure_s) {
    server->Push(camera, bgr, frame, exposure_s);
  };
  sim::Twin twin(scenario, options, sink);
  // The composed world as MJCF, for MuJoCo's own viewer.
  {
    char mj_error[1000] = "";
    const std::string world_xml = options.dir + "/world.xml";
    if (!mj_saveLastXML(world_xml.c_str(), twin.world().model(), mj_error, sizeof mj_error)) {
      std::fprintf(stderr, "twin: could not write %s: %s\n", world_xml.c_str(), mj_error);
    }
  }
  const std::string devices =
      twin.DevicesYaml(cameras->ClientPipeline(0), cameras->ClientPipeline(1), o.head_options);
  WriteFileWhole(options.dir + "/devices.yaml", devices);
  {
    YAML::Node doc = YAML::LoadFile(o.scenario);
    doc["devices"] = YAML::Load(devices)["devices"];
    YAML::Emitter out;
    out << doc;
    WriteFileWhole(options.dir + "/scenario.yaml", std::string(out.c_str()) + "\n");
  }
  // The control FIFO (opened read-write so that it never reads end-of-file between writers).
  const std::string control_path = options.dir + "/control";
  fs::remove(control_path, ec);
  int control_fd = -1;
  if (::mkfifo(control_path.c_str(), 0600) == 0) {
    control_fd = ::open(control_path.c_str(), O_RDWR | O_NONBLOCK);
  }
  std::string control_buffer;

  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);

  std::fprintf(stderr, "twin: %s at rate %g; ports in %s; cameras %s | %s\n", scenario.name.c_str(),
               o.rate, options.dir.c_str(), cameras->ClientPipeline(0).c_str(),
               cameras->ClientPipeline(1).c_str());
  std::fprintf(stderr, "twin: run against it with: hgrasp run %s/scenario.yaml --out DIR\n",
               options.dir.c_str());
  WriteFileWhole(options.dir + "/ready", "ready\n");
  const double t_start = twin.time();
  const auto run_control = [&](const std::string& command) {
    const std::string err = twin.Control(command);
    std::fprintf(stderr, "twin: t = %.3f s: %s%s%s\n", twin.time() - t_start, command.c_str(),
                 err.empty() ? "" : ": ", err.c_str());
  };
  twin.Run([&] {
    if (g_stop_signal != 0) return false;
    const double t = twin.time() - t_start;
    if (o.seconds && t >= *o.seconds) return false;
    for (std::size_t i = 0; i < schedule.size(); ++i) {
      if (!done[i] && t >= schedule[i].t_s) {
        done[i] = true;
        run_control(schedule[i].command);
      }
    }
    if (control_fd >= 0) {
      char buf[256];
      const ssize_t n = ::read(control_fd, buf, sizeof buf);
      if (n > 0) {
        control_buffer.append(buf, static_cast<size_t>(n));
        for (size_t nl; (nl = control_buffer.find('\n')) != std::string::npos;) {
          const std::string line = control_buffer.substr(0, nl);
          control_buffer.erase(0, nl + 1);
          if (!line.empty()) run_control(line);
        }
      }
    }
    return true;
  });
  if (control_fd >= 0) ::close(control_fd);
  fs::remove(control_path, ec);
  fs::remove(options.dir + "/ready", ec);
  nlohmann::json report = twin.Report();
  for (int c = 0; c < 2; ++c) {
    const drivers::GstStreamStats st = cameras->stats(c);
    report["cameras"][c == 0 ? "left" : "right"] = {
        {"port", cameras->port(c)}, {"pushed", st.pushed}, {"refused", st.refused}};
  }
  WriteFileWhole(options.dir + "/twin.json", report.dump(1) + "\n");
  const sim::TwinFrameCounts f = twin.frame_counts();
  std::fprintf(stderr,
               "twin: %.1f s served; %llu exposures, %llu rendered, %llu overruns (not rendered "
               "in time); mean render %.1f ms\n",
               twin.time() - t_start, static_cast<unsigned long long>(f.exposures),
               static_cast<unsigned long long>(f.rendered),
               static_cast<unsigned long long>(f.overruns),
               f.rendered ? 1e3 * f.render_s / f.rendered : 0.0);
  return 0;
}

}  // namespace hgrasp::app
