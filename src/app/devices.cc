#include "app/devices.h"

#include "biclops/biclops_head.h"
#include "camera/gst_stereo_camera.h"
#include "common/error.h"
#include "laser_board/board_devices.h"
#include "laser_board/laser_board.h"
#include "sensorhand/sensorhand_hand.h"
#include "serial/serial_port.h"
#include "val2/val2_arm.h"

namespace hgrasp::app {
namespace {

using device::Side;

drivers::SerialConfig SerialOf(const sim::DeviceSpec& d) {
  drivers::SerialConfig c;
  c.port = d.port;
  c.baud = d.baud;
  c.data_bits = d.framing[0] - '0';
  c.parity = d.framing[1] == 'E'   ? drivers::Parity::kEven
             : d.framing[1] == 'O' ? drivers::Parity::kOdd
                                   : drivers::Parity::kNone;
  c.stop_bits = d.framing[2] - '0';
  return c;
}

// "FILE:LINE" of a device's entry, for errors found when opening it.
std::string Where(const sim::Scenario& s, const sim::DeviceSpec& d) {
  return d.line > 0 ? s.path + ":" + std::to_string(d.line) : s.path;
}

// Opens a device's serial port; a port that cannot be opened is bad input (exit 2), named.
std::unique_ptr<drivers::ByteLink> OpenPort(const sim::Scenario& s, const std::string& key) {
  const sim::DeviceSpec& d = s.devices.at(key);
  std::string error;
  std::unique_ptr<drivers::SerialPort> port = drivers::SerialPort::Open(SerialOf(d), &error);
  if (!port) {
    throw InputError(Where(s, d), "devices." + key + ".port", d.port,
                     "a serial port that can be opened at " + std::to_string(d.baud) + " " +
                         d.framing + " (" + error + ")");
  }
  return port;
}

const sim::DeviceSpec* Spec(const sim::Scenario& s, const std::string& key) {
  const auto it = s.devices.find(key);
  return it == s.devices.end() || it->second.simulated() ? nullptr : &it->second;
}

}  // namespace

bool AllSimulated(const sim::Scenario& scenario) {
  for (const auto& [key, d] : scenario.devices) {
    if (!d.simulated()) return false;
  }
  return true;
}

device::RobotDevices MakeDevices(const sim::Scenario& s, sim::SimRobot* robot) {
  device::RobotDevices dev = robot->TakeDevices();
  for (Side side : {Side::kLeft, Side::kRight}) {
    const int i = static_cast<int>(side);
    const std::string name(device::ToString(side));
    if (Spec(s, "arm_" + name) != nullptr) {
      dev.arm[i] = std::make_unique<drivers::Val2Arm>(OpenPort(s, "arm_" + name));
    }
    if (Spec(s, "hand_" + name) != nullptr) {
      dev.hand[i] = std::make_unique<drivers::SensorHandHand>(OpenPort(s, "hand_" + name));
    }
  }
  if (Spec(s, "head") != nullptr) {
    dev.head = std::make_unique<drivers::BiclopsHead>(OpenPort(s, "head"));
  }
  // The laser and the LEDs hang on one board: one driver for both when both are real.
  std::shared_ptr<drivers::LaserBoard> board;
  for (const char* key : {"laser", "leds"}) {
    if (Spec(s, key) != nullptr && !board) {
      board = std::make_shared<drivers::LaserBoard>(OpenPort(s, key));
    }
  }
  if (Spec(s, "laser") != nullptr) dev.laser = std::make_unique<drivers::BoardStripeLaser>(board);
  if (Spec(s, "leds") != nullptr) dev.leds = std::make_unique<drivers::BoardLeds>(board);
  if (const sim::DeviceSpec* cameras = Spec(s, "cameras")) {
    // The scenario loader has checked that the laser is on the board.
    drivers::LatchSource latch = [board](drivers::ExposureLatch* out) {
      drivers::FrameLatch l;
      const device::Status status = board->LatestFrameLatch(&l);
      out->frame = l.frame;
      out->encoder_count = l.encoder_count;
      out->laser_on = l.laser_on;
      return status;
    };
    std::string error;
    auto camera = drivers::GstStereoCamera::Open({cameras->left, cameras->right}, latch,
                                                 dev.head.get(), &error);
    if (!camera) {
      throw InputError(Where(s, *cameras), "devices.cameras",
                       error.rfind("left", 0) == 0 ? cameras->left : cameras->right,
                       "GStreamer pipelines that open (" + error + ")");
    }
    dev.cameras = std::move(camera);
  }
  return dev;
}

}  // namespace hgrasp::app
