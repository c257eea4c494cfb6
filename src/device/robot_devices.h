#pragma once
/// @file Every device of the robot, as the pipeline gets them from the composition root
/// (src/app/), simulated or real.

#include <array>
#include <memory>

#include "device/arm.h"
#include "device/hand.h"
#include "device/head.h"
#include "device/leds.h"
#include "device/stereo_camera.h"
#include "device/stripe_laser.h"

namespace hgrasp::device {

struct RobotDevices {
  std::array<std::unique_ptr<Arm>, 2> arm;    ///< indexed by Side
  std::array<std::unique_ptr<Hand>, 2> hand;  ///< indexed by Side
  std::unique_ptr<Head> head;
  std::unique_ptr<StripeLaser> laser;
  std::unique_ptr<Leds> leds;
  std::unique_ptr<StereoCamera> cameras;

  Arm& ArmOf(Side s) { return *arm[static_cast<int>(s)]; }
  Hand& HandOf(Side s) { return *hand[static_cast<int>(s)]; }
};

}  // namespace hgrasp::device
