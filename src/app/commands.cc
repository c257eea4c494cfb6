#include "app/commands.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/output_dir.h"
#include "app/pictures.h"
#include "common/error.h"
#include "common/write_file.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"

namespace hgrasp::app {
namespace {

namespace fs = std::filesystem;

bool Interactive() { return isatty(STDERR_FILENO) != 0; }

void Progress(const std::string& what) {
  if (Interactive()) spdlog::info("{}", what);
}

// Depth as a 16-bit PNG in units of 0.1 mm (0: no surface).
cv::Mat DepthPng(const cv::Mat& depth_m) {
  cv::Mat out;
  depth_m.convertTo(out, CV_16U, 1e4);
  return out;
}

// Depth in false colour for people: near red, far blue, nothing black.
cv::Mat DepthView(const cv::Mat& depth_m) {
  double lo = 1e9, hi = 0;
  for (int r = 0; r < depth_m.rows; ++r)
    for (int c = 0; c < depth_m.cols; ++c)
      if (const float z = depth_m.at<float>(r, c); z > 0)
        lo = std::min(lo, double(z)), hi = std::max(hi, double(z));
  cv::Mat grey(depth_m.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < depth_m.rows; ++r)
    for (int c = 0; c < depth_m.cols; ++c)
      if (const float z = depth_m.at<float>(r, c); z > 0)
        grey.at<uchar>(r, c) = cv::saturate_cast<uchar>(255.0 * (hi - z) / std::max(hi - lo, 1e-9));
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_JET);
  colour.setTo(cv::Scalar::all(0), depth_m <= 0);
  return colour;
}

// Labels as a 16-bit PNG of geom id + 1 (0: nothing), and a colour view.
cv::Mat LabelPng(const cv::Mat& label) {
  cv::Mat out;
  label.convertTo(out, CV_16U, 1.0, 1.0);
  return out;
}

cv::Mat LabelView(const cv::Mat& label) {
  cv::Mat out(label.size(), CV_8UC3, cv::Scalar::all(0));
  for (int r = 0; r < label.rows; ++r)
    for (int c = 0; c < label.cols; ++c)
      if (const int g = label.at<int>(r, c); g >= 0) {
        const unsigned h = static_cast<unsigned>(g + 1) * 2654435761u;
        out.at<cv::Vec3b>(r, c) =
            cv::Vec3b(64 + (h & 127), 64 + ((h >> 8) & 127), 64 + ((h >> 16) & 127));
      }
  return out;
}

// `hgrasp render` drives the simulated devices, which answer every call: a status other than ok
// there is a bug in the simulator, not a device's failure.
void SimulatedOk(device::Status s, const char* call) {
  HGRASP_DEMAND_MSG(s == device::Status::kOk, call);
}

// Grabs frames until the laser has reached its target.
device::StereoFrame GrabWhenSettled(device::RobotDevices& dev) {
  device::StereoFrame frame;
  device::StripeLaserState laser;
  for (int i = 0; i < 1000; ++i) {
    SimulatedOk(dev.laser->Read(&laser), "laser read");
    SimulatedOk(dev.cameras->Grab(&frame), "cameras grab");
    if (!laser.moving) break;
  }
  return frame;
}

}  // namespace

int Render(const RenderOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  sim::Scenario scenario = sim::LoadScenario(o.scenario);  // InputError -> exit 2 in main
  OutputDir out(o.out_dir);
  Progress("building the world of " + scenario.name);
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  spdlog::info("rendering with {}", robot.rig().renderer().DeviceDescription());

  struct Output {
    std::string name;
    cv::Mat image;
  };
  std::vector<Output> outputs;

  // Ambient light only.
  SimulatedOk(dev.laser->SetLaser(false), "laser off");
  device::StereoFrame frame;
  SimulatedOk(dev.cameras->Grab(&frame), "cameras grab");
  outputs.push_back({"left.png", frame.left});
  outputs.push_back({"right.png", frame.right});
  for (int cam : {sim::kLeft, sim::kRight}) {
    const std::string side = cam == sim::kLeft ? "left" : "right";
    const sim::CameraView& view = robot.rig().View(cam);
    outputs.push_back({"depth_" + side + ".png", DepthPng(view.images.depth)});
    outputs.push_back({"depth_" + side + "_view.png", DepthView(view.images.depth)});
    outputs.push_back({"labels_" + side + ".png", LabelPng(view.images.label)});
    outputs.push_back({"labels_" + side + "_view.png", LabelView(view.images.label)});
  }

  // The stripe at each requested encoder count.
  SimulatedOk(dev.laser->SetLaser(true), "laser on");
  for (std::int32_t count : o.encoder_counts) {
    Progress("stripe at encoder count " + std::to_string(count));
    if (dev.laser->MoveTo(count, 9000.0) != device::Status::kOk) {
      throw InputError("", "--encoder", std::to_string(count),
                       "a count within the laser's range (about +-4500)");
    }
    frame = GrabWhenSettled(dev);
    // Built by appending: GCC 12 warns falsely (-Wrestrict) on "_" + to_string(...) + ".png".
    std::string suffix = "_";
    suffix.append(std::to_string(count)).append(".png");
    outputs.push_back({"left_stripe" + suffix, frame.left});
    outputs.push_back({"right_stripe" + suffix, frame.right});
    if (count == o.encoder_counts.front()) {
      cv::Mat pair;
      cv::hconcat(frame.left, frame.right, pair);
      outputs.push_back({"stereo_pair.png", pair});
    }
  }
  nlohmann::json truth = sim::TruthJson(robot.world(), robot.rig(), o.encoder_counts);
  truth["scenario"] = scenario.name;
  truth["seed"] = scenario.seed;
  truth["renderer"] = robot.rig().renderer().DeviceDescription();

  for (const Output& output : outputs) WritePng(output.image, out.Path(output.name));
  WriteFileWhole(out.Path("truth.json"), truth.dump(2) + "\n");
  out.Commit();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  spdlog::info("render: {} images and truth.json in {} ({:.2f} s)", outputs.size(), o.out_dir,
               wall);
  return 0;
}

}  // namespace hgrasp::app
